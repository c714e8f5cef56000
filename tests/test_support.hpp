#pragma once
// Helpers shared by the tests: single bodies and joints, fixed-step integration.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/line_fit.hpp"

namespace mbsflow::test {

// Largest distance between the centres of mass of the same body in two states.
inline double position_gap(const MultibodySystem& sys, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return largest_position_gap(sys.layout(), a, b);
}

inline Body make_body(const char* name, double mass, Vec6 inertia, Vec3 position = {}) {
  Body b;
  b.name = name;
  b.mass = mass;
  b.inertia = inertia;
  b.position = position;
  return b;
}

inline Joint make_bushing(int body1, int body2, Vec3 p1, Vec3 p2, Vec6 k, Vec6 c = {}) {
  Joint j;
  j.name = "j" + std::to_string(body2);
  j.body1 = body1;
  j.body2 = body2;
  j.point1 = p1;
  j.point2 = p2;
  j.stiffness = k;
  j.damping = c;
  return j;
}

inline Joint make_joint(JointType type, int body1, int body2, Vec3 p1, Vec3 p2) {
  Joint j = make_bushing(body1, body2, p1, p2, {});
  j.name = std::string(joint_type_name(type)) + std::to_string(body2);
  j.type = type;
  return j;
}

// theta'' = accel(theta) from t = 0 by classic RK4 with step h, sampled at the given
// times (multiples of h): the reduced model of a one-degree-of-freedom mechanism.
template <class F>
std::vector<double> reduced_rk4(F accel, double theta, double rate, const std::vector<double>& times, double h) {
  std::vector<double> out;
  double t = 0.0;
  for (double target : times) {
    const long n = std::lround((target - t) / h);
    for (long k = 0; k < n; ++k) {
      const double k1 = rate, l1 = accel(theta);
      const double k2 = rate + 0.5 * h * l1, l2 = accel(theta + 0.5 * h * k1);
      const double k3 = rate + 0.5 * h * l2, l3 = accel(theta + 0.5 * h * k2);
      const double k4 = rate + h * l3, l4 = accel(theta + h * k3);
      theta += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      rate += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
    }
    t += static_cast<double>(n) * h;
    out.push_back(theta);
  }
  return out;
}

// Integrates with RK4 and the mechanics' after-step projection; calls f(t, y) after each step.
template <class F>
Eigen::VectorXd integrate_rk4(MultibodySystem& sys, double t_end, long steps, F f) {
  Eigen::VectorXd y = sys.initial_state();
  Rk4 rk(sys.dimension());
  const double h = t_end / static_cast<double>(steps);
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * h;
    rk.step(sys, t, h, y);
    sys.after_step(t + h, y);
    f(t + h, y);
  }
  return y;
}

inline Eigen::VectorXd integrate_rk4(MultibodySystem& sys, double t_end, long steps) {
  return integrate_rk4(sys, t_end, steps, [](double, const Eigen::VectorXd&) {});
}

// The entries of the right-hand side's Jacobian at (t, y), by forward differences of
// every state in turn, that lie outside and inside `pattern` (the implicit methods'
// colouring would miss the former); each outside one is reported.
struct PatternCount {
  long outside = 0, inside = 0;
};

inline PatternCount count_against_pattern(MultibodySystem& sys, double t, const Eigen::VectorXd& y,
                                          const Eigen::SparseMatrix<double>& pattern) {
  const Eigen::Index n = sys.dimension();
  const Eigen::MatrixXd dense = Eigen::MatrixXd(pattern);
  Eigen::VectorXd f0(n), f1(n);
  sys.rhs(t, y, f0);
  PatternCount count;
  for (Eigen::Index c = 0; c < n; ++c) {
    const double h = 1e-7 * std::max(1.0, std::abs(y[c]));
    Eigen::VectorXd yp = y;
    yp[c] += h;
    sys.rhs(t, yp, f1);
    for (Eigen::Index r = 0; r < n; ++r) {
      if (std::abs(f1[r] - f0[r]) / h <= 1e-6) continue;
      if (dense(r, c) == 0.0) {
        ++count.outside;
        UNSCOPED_INFO("d f[" << r << "] / d y[" << c << "] = " << (f1[r] - f0[r]) / h << " is outside the pattern");
      } else {
        ++count.inside;
      }
    }
  }
  return count;
}

}  // namespace mbsflow::test
