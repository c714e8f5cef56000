#include <catch2/catch.hpp>
#include <cmath>

#include "rotation.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

TEST_CASE("natural-frequency form: stiffness and damping from the joined masses", "[graph]") {
  Model model;
  model.bodies.push_back(make_body("a", 2.0, {1, 2, 3}));
  model.bodies.push_back(make_body("b", 6.0, {3, 2, 1}));
  Joint to_ground = make_bushing(ground, 0, {}, {}, {});
  set_bushing_from_frequency(model, to_ground, 10.0, 0.1);
  CHECK(to_ground.stiffness[0] == Approx(2.0 * 100));
  CHECK(to_ground.damping[0] == Approx(2 * 0.1 * 10 * 2.0));
  CHECK(to_ground.stiffness[5] == Approx(3.0 * 100));
  Joint between = make_bushing(0, 1, {}, {}, {});
  set_bushing_from_frequency(model, between, 10.0, 0.1);
  CHECK(between.stiffness[1] == Approx(1.5 * 100));  // reduced mass 2*6/8
  CHECK(between.stiffness[3] == Approx(0.75 * 100));  // reduced inertia 1*3/4
}

TEST_CASE("two free bodies joined in natural-frequency form oscillate at Omega", "[graph]") {
  const double omega = 15.0, x0 = 0.05;
  Model model;
  model.bodies.push_back(make_body("a", 2.0, {1, 1, 1}));
  model.bodies.push_back(make_body("b", 6.0, {1, 1, 1}, {1.0 + x0, 0, 0}));
  Joint j = make_bushing(0, 1, {1, 0, 0}, {0, 0, 0}, {});
  set_bushing_from_frequency(model, j, omega, 0.0);
  model.joints.push_back(j);
  MultibodySystem sys(model);
  double max_err = 0.0;
  integrate_rk4(sys, 1.0, 10000, [&](double t, const Eigen::VectorXd& y) {
    const double gap = y[sys.layout().position(1)] - y[0] - 1.0;
    max_err = std::max(max_err, std::abs(gap - x0 * std::cos(omega * t)));
  });
  CHECK(max_err < 1e-9);
}

TEST_CASE("default joint frame on body2 leaves a rotated joint unstressed", "[graph]") {
  Model model;
  Body a = make_body("a", 1.0, {1, 1, 1});
  a.orientation = {std::cos(0.2), 0, std::sin(0.2), 0};
  Body b = make_body("b", 1.0, {1, 1, 1}, {1, 0, 0});
  b.orientation = {std::cos(0.9), std::sin(0.9) * 0.6, 0, std::sin(0.9) * 0.8};
  model.bodies = {a, b};
  Joint j = make_bushing(0, 1, {0, 0, 0}, {0, 0, 0}, {0, 0, 0, 50, 60, 70});
  j.frame2 = rest_frame2(model, j);
  model.joints.push_back(j);
  MultibodySystem sys(model);
  Eigen::VectorXd dy(sys.dimension());
  sys.rhs(0.0, sys.initial_state(), dy);
  CHECK(dy.segment<3>(sys.layout().angular_velocity(0)).norm() < 1e-13);
  CHECK(dy.segment<3>(sys.layout().angular_velocity(1)).norm() < 1e-13);
  CHECK(sys.energy(0.0, sys.initial_state()).elastic < 1e-26);
}

TEST_CASE("quaternions are renormalised after each step by the mechanics", "[graph]") {
  Model model;
  Body b = make_body("spin", 1.0, {1, 2, 3});
  b.angular_velocity = {5, 7, -3};
  model.bodies.push_back(b);
  MultibodySystem sys(model);
  const Eigen::Index q = sys.layout().orientation(0);
  // after_step maps any quaternion onto the unit sphere, keeping its direction.
  Eigen::VectorXd off = sys.initial_state();
  off.segment<4>(q) = Eigen::Vector4d(2.0, 0.2, -0.4, 0.6);
  sys.after_step(0.0, off);
  CHECK(std::abs(off.segment<4>(q).norm() - 1.0) < 1e-15);
  CHECK((off.segment<4>(q) - Eigen::Vector4d(2.0, 0.2, -0.4, 0.6).normalized()).norm() < 1e-15);
  // After each of the steps the norm is 1 to rounding...
  double worst = 0.0;
  const Eigen::VectorXd y = integrate_rk4(sys, 1.0, 100, [&](double, const Eigen::VectorXd& x) {
    worst = std::max(worst, std::abs(x.segment<4>(q).norm() - 1.0));
  });
  CHECK(worst < 1e-15);
  CHECK(std::abs(y.segment<4>(q).norm() - 1.0) < 1e-15);
  // ...while RK4 alone, with the same steps, lets it drift: the mechanics' renormalisation
  // is what keeps it.
  Eigen::VectorXd raw = sys.initial_state();
  Rk4 rk(sys.dimension());
  for (int k = 0; k < 100; ++k) rk.step(sys, 0.01 * k, 0.01, raw);
  CHECK(std::abs(raw.segment<4>(q).norm() - 1.0) > 1e-10);
}
