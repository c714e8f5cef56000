// Reduced equations of the IFToMM benchmark mechanisms in generalised coordinates, from
// the benchmarks' own data (not from the example files), integrated with RK4.
#include "mbsflow/runtime/iftomm_reference.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

constexpr double g = 9.81;

// x' = f(x) with classical RK4 at step h, sampled at `times` (from t = 0, multiples of h).
template <int N, class F>
std::vector<Eigen::Matrix<double, N, 1>> rk4_samples(F f, Eigen::Matrix<double, N, 1> x, const std::vector<double>& times,
                                                     double h) {
  using V = Eigen::Matrix<double, N, 1>;
  std::vector<V> out;
  out.reserve(times.size());
  double t = 0.0;
  for (double target : times) {
    for (long n = std::lround((target - t) / h); n > 0; --n, t += h) {
      const V k1 = f(x), k2 = f(V(x + 0.5 * h * k1)), k3 = f(V(x + 0.5 * h * k2)), k4 = f(V(x + h * k3));
      x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    out.push_back(x);
  }
  return out;
}

int body_named(const MultibodySystem& sys, const char* name) {
  const std::optional<int> i = find_body(sys.model(), name);
  if (!i || *i == ground) throw InputError(std::string("the IFToMM model has no body '") + name + "'");
  return *i;
}

Eigen::Vector3d position(const MultibodySystem& sys, const Eigen::VectorXd& y, int i) {
  return y.segment<3>(sys.layout().position(i));
}

Eigen::Quaterniond orientation(const MultibodySystem& sys, const Eigen::VectorXd& y, int i) {
  const Eigen::Vector4d q = y.segment<4>(sys.layout().orientation(i));
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
}

// A01 and A02: the crank angle phi from +x obeys phi'' = -c cos(phi); the benchmark's point
// (`on_body`, body frame of body 0) should be at (cos phi, sin phi).
IftommCheck check_crank(double c, double phi0, double rate0, const Eigen::Vector3d& on_body, MultibodySystem& sys,
                        const std::vector<double>& times, const std::vector<Eigen::VectorXd>& states) {
  const auto ref = rk4_samples<2>([c](const Eigen::Vector2d& s) { return Eigen::Vector2d(s[1], -c * std::cos(s[0])); },
                                  Eigen::Vector2d(phi0, rate0), times, 1e-4);
  IftommCheck out;
  const double e0 = sys.energy(times.front(), states.front()).total();
  for (std::size_t k = 0; k < times.size(); ++k) {
    const Eigen::Vector3d p = position(sys, states[k], 0) + orientation(sys, states[k], 0) * on_body;
    out.error = std::max(out.error, std::hypot(p[0] - std::cos(ref[k][0]), p[1] - std::sin(ref[k][0])));
    out.drift = std::max(out.drift, std::abs(sys.energy(times[k], states[k]).total() - e0));
  }
  return out;
}

// A05, the stiff flyball governor (vertical shaft on z, gravity -z). The data of the
// benchmark: shaft, rods 1 x 0.01 x 0.01 m and slider 0.1 m cube of density 3000 kg/m^3,
// 5 kg point masses at the rods' ends, spring-dampers K = 8e5 N/m, C = 4e4 N s/m, rest
// length 0.5 m from the slider's centre to the rods at s = 0.5 m from their hinges at the
// shaft's top (z = 1), rods 30 degrees from the shaft; the initial spin is ours.
struct Flyball {
  static constexpr double rho = 3000.0, bar = 0.3, ball = 5.0, s = 0.5, k = 8e5, c = 4e4, rest = 0.5;
  static constexpr double rod_mass = bar + ball;
  static constexpr double com = (bar * 0.5 + ball * 1.0) / rod_mass;  // from the hinge
  static constexpr double slider_mass = rho * 1e-3;
  // Rod about its centre of mass: along the bar (A) and across it (B).
  static constexpr double a = bar * 2e-4 / 12;
  static constexpr double b = bar * (1 + 1e-4) / 12 + bar * (0.5 - com) * (0.5 - com) + ball * (1 - com) * (1 - com);
  static constexpr double rod_pitch = rod_mass * com * com + b;   // about the hinge axis
  static constexpr double spin_axis = a + slider_mass * 0.02 / 12;  // shaft and slider about z

  // q = (phi, theta1, theta2, z): shaft angle, rods' angles from the downward shaft,
  // slider height; x = (q, q').
  using V = Eigen::Matrix<double, 8, 1>;
  static V rates(const V& x) {
    const double w = x[4];
    double spin = spin_axis, spin_rate = 0.0, fz = -slider_mass * g;
    V d = V::Zero();
    d.head<4>() = x.tail<4>();
    for (int i = 1; i <= 2; ++i) {
      const double th = x[i], dth = x[4 + i], sn = std::sin(th), cs = std::cos(th);
      // Rod's moment of inertia about z: J = B' sin^2 + A cos^2, B' = rod_pitch.
      const double dj = 2 * (rod_pitch - a) * sn * cs;
      spin += rod_pitch * sn * sn + a * cs * cs;
      spin_rate += dj * dth;
      const double h = 1 - s * cs - x[3], len = std::hypot(s * sn, h);
      const double dl_th = (s * s * sn * cs + h * s * sn) / len, dl_z = -h / len;
      const double f = k * (len - rest) + c * (dl_th * dth + dl_z * x[7]);
      d[4 + i] = (-f * dl_th - rod_mass * g * com * sn + 0.5 * w * w * dj) / rod_pitch;
      fz -= f * dl_z;
    }
    d[4] = -spin_rate * w / spin;  // the angular momentum spin * w is conserved
    d[7] = fz / slider_mass;
    return d;
  }
};

Eigen::Vector3d rod_centre(const Flyball::V& x, int i, double sign) {
  const double r = Flyball::com * std::sin(x[i]);
  return {sign * r * std::cos(x[0]), sign * r * std::sin(x[0]), 1 - Flyball::com * std::cos(x[i])};
}

// Angular momentum about the world z axis through the origin.
double spin_momentum(const MultibodySystem& sys, const Eigen::VectorXd& y) {
  double l = 0.0;
  for (int i = 0; i < sys.layout().bodies; ++i) {
    const Body& b = sys.model().bodies[static_cast<std::size_t>(i)];
    const Eigen::Matrix3d inertia = inertia_matrix(b.inertia);
    const Eigen::Vector3d w = y.segment<3>(sys.layout().angular_velocity(i));
    const Eigen::Vector3d v = y.segment<3>(sys.layout().velocity(i));
    l += (b.mass * position(sys, y, i).cross(v) + orientation(sys, y, i) * (inertia * w))[2];
  }
  return l;
}

IftommCheck check_flyball(MultibodySystem& sys, const std::vector<double>& times, const std::vector<Eigen::VectorXd>& states) {
  const double theta0 = std::numbers::pi / 6, spin0 = 2 * std::numbers::pi;
  Flyball::V x0;
  x0 << 0, theta0, theta0, 1 - 2 * Flyball::s * std::cos(theta0), spin0, 0, 0, 0;
  const auto ref = rk4_samples<8>(Flyball::rates, x0, times, 1e-5);
  const int rod1 = body_named(sys, "rod1"), rod2 = body_named(sys, "rod2"), slider = body_named(sys, "slider");
  IftommCheck out;
  const double l0 = spin_momentum(sys, states.front());
  for (std::size_t k = 0; k < times.size(); ++k) {
    const Eigen::VectorXd& y = states[k];
    out.error = std::max({out.error, (position(sys, y, rod1) - rod_centre(ref[k], 1, 1.0)).norm(),
                          (position(sys, y, rod2) - rod_centre(ref[k], 2, -1.0)).norm(),
                          std::abs(position(sys, y, slider)[2] - ref[k][3])});
    out.drift = std::max(out.drift, std::abs(spin_momentum(sys, y) - l0));
  }
  return out;
}

constexpr double four_bars = 40.0;

constexpr std::array<IftommInfo, 3> problems{{
    {IftommProblem::a01_pendulum, "A01 pendulum, 2000 s", "iftomm_a01_pendulum.json", "mass point", "energy J",
     "OpenSim 3.2: 0.637 s for 10 s (i5-4570)"},
    {IftommProblem::a02_n_four_bar, "A02 N-four-bar, N=40, 20 s", "iftomm_a02_n_four_bar.json", "point B0", "energy J",
     "OpenSim 3.2: 0.455 s for N=2, 10 s (i5-4570)"},
    {IftommProblem::a05_flyball_governor, "A05 flyball governor, 10 s", "iftomm_a05_flyball_governor.json",
     "rod centres, slider height", "spin momentum N m s", "no published timing at hand"},
}};

}  // namespace

std::span<const IftommInfo> iftomm_problems() { return problems; }

IftommCheck check_iftomm(IftommProblem p, MultibodySystem& sys, const std::vector<double>& times,
                         const std::vector<Eigen::VectorXd>& states) {
  if (times.empty() || times.size() != states.size()) throw InputError("check_iftomm: no snapshots");
  switch (p) {
    case IftommProblem::a01_pendulum:
      return check_crank(g, std::numbers::pi, 0.0, Eigen::Vector3d::Zero(), sys, times, states);
    case IftommProblem::a02_n_four_bar: {
      // The links stay a parallelogram: M phi'' = -dV/dphi with M = m L^2 ((N+1)/3 + N) and
      // V = m g L ((N+1)/2 + N) sin(phi); the point is the top of crank 0, 0.5 m along its x.
      const double c = g * ((four_bars + 1) / 2 + four_bars) / ((four_bars + 1) / 3 + four_bars);
      return check_crank(c, std::numbers::pi / 2, -1.0, Eigen::Vector3d(0.5, 0, 0), sys, times, states);
    }
    case IftommProblem::a05_flyball_governor: return check_flyball(sys, times, states);
  }
  throw InputError("check_iftomm: unknown problem");
}

}  // namespace mbsflow
