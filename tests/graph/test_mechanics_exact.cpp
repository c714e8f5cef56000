// Single-body motions with closed-form solutions.
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/graph/multibody_system.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

TEST_CASE("body on a linear bushing to ground: closed-form damped oscillation", "[graph][exact]") {
  const double m = 2.0, k = 800.0, zeta = 0.1, x0 = 1.0;
  const double w = std::sqrt(k / m), c = 2 * zeta * std::sqrt(k * m), wd = w * std::sqrt(1 - zeta * zeta);
  Model model;
  model.bodies.push_back(make_body("b", m, {0.5, 0.5, 0.5}, {x0, 0, 0}));
  model.joints.push_back(make_bushing(ground, 0, {0, 0, 0}, {0, 0, 0}, {k, k, k, 0, 0, 0}, {c, c, c, 0, 0, 0}));
  MultibodySystem sys(model);
  double max_err = 0.0;
  integrate_rk4(sys, 2.0, 20000, [&](double t, const Eigen::VectorXd& y) {
    const double exact = std::exp(-zeta * w * t) * (x0 * std::cos(wd * t) + zeta * w * x0 / wd * std::sin(wd * t));
    max_err = std::max(max_err, std::abs(y[0] - exact));
  });
  INFO("max error " << max_err);
  CHECK(max_err < 1e-8);
}

TEST_CASE("rotational bushing axis: closed-form damped torsional oscillation", "[graph][exact]") {
  const double jz = 0.5, kr = 50.0, zeta = 0.05, w0 = 0.5;
  const double w = std::sqrt(kr / jz), c = 2 * zeta * std::sqrt(kr * jz), wd = w * std::sqrt(1 - zeta * zeta);
  Model model;
  Body b = make_body("b", 1.0, {0.3, 0.4, jz});
  b.angular_velocity = {0, 0, w0};
  model.bodies.push_back(b);
  model.joints.push_back(make_bushing(ground, 0, {0, 0, 0}, {0, 0, 0}, {1e3, 1e3, 1e3, kr, kr, kr}, {0, 0, 0, c, c, c}));
  MultibodySystem sys(model);
  double max_err = 0.0;
  integrate_rk4(sys, 2.0, 20000, [&](double t, const Eigen::VectorXd& y) {
    const auto q = y.segment<4>(sys.layout().orientation(0));
    const double angle = 2 * std::atan2(q[3], q[0]);
    const double exact = w0 / wd * std::exp(-zeta * w * t) * std::sin(wd * t);
    max_err = std::max(max_err, std::abs(angle - exact));
  });
  INFO("max error " << max_err);
  CHECK(max_err < 1e-9);
}

TEST_CASE("free fall under gravity is exact", "[graph][exact]") {
  Model model;
  model.gravity = {0.0, -9.81, 0.0};
  Body b = make_body("b", 3.0, {1, 2, 2.5}, {1, 2, 3});
  b.velocity = {1.5, 4.0, -0.5};
  model.bodies.push_back(b);
  MultibodySystem sys(model);
  const double t = 3.0;
  const Eigen::VectorXd y = integrate_rk4(sys, t, 30);
  CHECK(y[0] == Approx(1 + 1.5 * t).epsilon(1e-14));
  CHECK(y[1] == Approx(2 + 4.0 * t - 0.5 * 9.81 * t * t).epsilon(1e-14));
  CHECK(y[2] == Approx(3 - 0.5 * t).epsilon(1e-14));
  CHECK(y[sys.layout().velocity(0) + 1] == Approx(4.0 - 9.81 * t).epsilon(1e-14));
}

TEST_CASE("harmonic force on a free body: closed-form motion", "[graph][exact]") {
  const double m = 2.0, f0 = 3.0, hz = 0.5, w = 2 * M_PI * hz;
  Model model;
  model.bodies.push_back(make_body("b", m, {1, 1, 1}));
  Load l;
  l.body = 0;
  l.force = {f0, 0, 0};
  l.function = TimeFunction::harmonic(1.0, hz);
  model.loads.push_back(l);
  MultibodySystem sys(model);
  const double t = 1.7;
  const Eigen::VectorXd y = integrate_rk4(sys, t, 2000);
  CHECK(y[0] == Approx(f0 / (m * w * w) * (w * t - std::sin(w * t))).epsilon(1e-10));
}

TEST_CASE("force at an offset point in the body frame gives the moment about the centre", "[graph][exact]") {
  Model model;
  Body b = make_body("b", 2.0, {1, 2, 4});
  const double half = std::sqrt(0.5);
  b.orientation = {half, 0, 0, half};  // 90 degrees about z: body x is world y
  model.bodies.push_back(b);
  Load l;
  l.body = 0;
  l.force = {0, 3, 0};  // body frame: world -x
  l.point = {1, 0, 0};  // body frame: world +y
  l.body_frame = true;
  model.loads.push_back(l);
  MultibodySystem sys(model);
  Eigen::VectorXd dy(sys.dimension());
  sys.rhs(0.0, sys.initial_state(), dy);
  const StateLayout& s = sys.layout();
  CHECK(dy[s.velocity(0)] == Approx(-1.5));
  // Moment in the body frame: (1,0,0) x (0,3,0) = (0,0,3); J_zz = 4.
  CHECK(dy[s.angular_velocity(0) + 2] == Approx(0.75));
  CHECK(std::abs(dy[s.angular_velocity(0)]) < 1e-15);
}

TEST_CASE("kinematic excitation: base-excited oscillator matches the closed form", "[graph][exact]") {
  const double m = 1.0, k = 400.0, u0 = 0.01, hz = 1.3;
  const double w = std::sqrt(k / m), W = 2 * M_PI * hz;
  Model model;
  model.bodies.push_back(make_body("base", 5.0, {1, 1, 1}));
  Body mass = make_body("mass", m, {1, 1, 1}, {0, 1, 0});
  mass.velocity = {2.0, 0, 0};  // moving with the base
  model.bodies.push_back(mass);
  model.joints.push_back(make_bushing(0, 1, {0, 1, 0}, {0, 0, 0}, {k, k, k, 0, 0, 0}));
  Driver d;
  d.body = 0;
  d.velocity = {2.0, 0, 0};
  d.displacement[1] = TimeFunction::harmonic(u0, hz);
  model.drivers.push_back(d);
  MultibodySystem sys(model);
  double max_err = 0.0, max_base = 0.0;
  integrate_rk4(sys, 2.0, 20000, [&](double t, const Eigen::VectorXd& y) {
    // Relative to the base's steady drift in x, the mass follows y'' = -w^2 (y - 1 - u(t)).
    const double exact = 1 + u0 * w * w / (w * w - W * W) * (std::sin(W * t) - W / w * std::sin(w * t));
    max_err = std::max(max_err, std::abs(y[sys.layout().position(1) + 1] - exact));
    max_err = std::max(max_err, std::abs(y[sys.layout().position(1)] - 2.0 * t));
    max_base = std::max(max_base, std::abs(y[1] - u0 * std::sin(W * t)) + std::abs(y[0] - 2.0 * t));
  });
  CHECK(max_base < 1e-15);
  CHECK(max_err < 1e-9);
}

TEST_CASE("preload holds a body at rest under gravity", "[graph][exact]") {
  Model model;
  model.gravity = {0, -9.81, 0};
  model.bodies.push_back(make_body("b", 4.0, {1, 1, 1}, {0, 1, 0}));
  Joint j = make_bushing(ground, 0, {0, 1, 0}, {0, 0, 0}, {1e4, 1e4, 1e4, 10, 10, 10});
  j.preload = {0, 4.0 * 9.81, 0, 0, 0, 0};
  model.joints.push_back(j);
  MultibodySystem sys(model);
  const Eigen::VectorXd y = integrate_rk4(sys, 1.0, 1000);
  CHECK((y - sys.initial_state()).norm() < 1e-12);
}

namespace {
// Complete elliptic integral of the first kind by the arithmetic-geometric mean.
double elliptic_k(double k) {
  double a = 1.0, b = std::sqrt(1 - k * k);
  for (int i = 0; i < 40; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return M_PI / (2 * a);
}
}  // namespace

TEST_CASE("stiff bushing pendulum swings with the period of the rigid pendulum", "[graph][exact]") {
  const double m = 1.0, L = 1.0, jz = 0.02, g = 9.81, theta0 = 20.0 * M_PI / 180.0;
  Model model;
  model.gravity = {0, -g, 0};
  Body b = make_body("bob", m, {jz, jz, jz}, {L * std::sin(theta0), -L * std::cos(theta0), 0});
  b.orientation = {std::cos(theta0 / 2), 0, 0, std::sin(theta0 / 2)};
  model.bodies.push_back(b);
  // Pivot at the origin, attached at the body's top; stiff in translation, free in rotation.
  model.joints.push_back(make_bushing(ground, 0, {0, 0, 0}, {0, L, 0}, {1e7, 1e7, 1e7, 0, 0, 0}));
  MultibodySystem sys(model);
  const double ip = jz + m * L * L;
  const double period = 4 * std::sqrt(ip / (m * g * L)) * elliptic_k(std::sin(theta0 / 2));
  std::vector<double> crossings;  // upward zero crossings of the angle
  double prev_angle = theta0, prev_t = 0.0;
  integrate_rk4(sys, 2.2 * period, 44000, [&](double t, const Eigen::VectorXd& y) {
    const double angle = std::atan2(y[0], -y[1]);
    if (prev_angle < 0.0 && angle >= 0.0) crossings.push_back(prev_t + (t - prev_t) * (-prev_angle) / (angle - prev_angle));
    prev_angle = angle;
    prev_t = t;
  });
  REQUIRE(crossings.size() == 2);
  const double measured = crossings[1] - crossings[0];
  INFO("measured " << measured << " s, rigid pendulum " << period << " s");
  CHECK(std::abs(measured / period - 1.0) < 0.005);
}
