// Conservation laws: energy, linear and angular momentum.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/graph/generators.hpp"
#include "rotation.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

struct Momentum {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();  // world, about the origin
};

Momentum momentum(const Model& m, const StateLayout& s, const Eigen::VectorXd& y) {
  Momentum p;
  for (Eigen::Index i = 0; i < s.bodies; ++i) {
    const Body& b = m.bodies[static_cast<std::size_t>(i)];
    const Vec6& in = b.inertia;
    Eigen::Matrix3d j;
    j << in[0], in[3], in[4], in[3], in[1], in[5], in[4], in[5], in[2];
    const Eigen::Matrix3d r = rotation_matrix(y.segment<4>(s.orientation(i)));
    const Eigen::Vector3d v = y.segment<3>(s.velocity(i));
    p.linear += b.mass * v;
    p.angular += y.segment<3>(s.position(i)).cross(b.mass * v) + r * (j * y.segment<3>(s.angular_velocity(i)));
  }
  return p;
}

}  // namespace

TEST_CASE("torque-free asymmetric body conserves energy and angular momentum, and flips", "[graph][conservation]") {
  Model model;
  Body b = make_body("top", 1.0, {1.0, 2.0, 3.0});
  b.angular_velocity = {0.1, 1.0, 0.1};  // near the unstable intermediate axis
  model.bodies.push_back(b);
  MultibodySystem sys(model);
  const Eigen::VectorXd y0 = sys.initial_state();
  const double e0 = sys.energy(0, y0).kinetic;
  const Eigen::Vector3d l0 = momentum(model, sys.layout(), y0).angular;
  double max_e = 0, max_l = 0, min_wy = 1;
  integrate_rk4(sys, 10.0, 10000, [&](double t, const Eigen::VectorXd& y) {
    max_e = std::max(max_e, std::abs(sys.energy(t, y).kinetic / e0 - 1));
    max_l = std::max(max_l, (momentum(model, sys.layout(), y).angular - l0).norm() / l0.norm());
    min_wy = std::min(min_wy, y[sys.layout().angular_velocity(0) + 1]);
  });
  INFO("energy drift " << max_e << ", angular momentum drift " << max_l << ", min w_y " << min_wy);
  CHECK(max_e < 1e-9);
  CHECK(max_l < 1e-9);
  CHECK(min_wy < -0.9);  // the intermediate-axis (Dzhanibekov) flip
}

TEST_CASE("two bodies on an anisotropic bushing: energy and momenta conserved at large rotations",
          "[graph][conservation]") {
  Model model;
  model.bodies.push_back(make_body("a", 2.0, {0.2, 0.3, 0.25, 0.01, 0.0, -0.02}));
  Body b = make_body("b", 1.5, {0.1, 0.15, 0.12}, {1.0, 0.2, 0.0});
  b.orientation = {std::cos(0.4), std::sin(0.4), 0.0, 0.0};
  b.velocity = {0.0, 0.3, -0.2};
  b.angular_velocity = {3.0, 1.0, 2.0};
  model.bodies.push_back(b);
  model.bodies[0].angular_velocity = {0.0, 0.0, -1.0};
  Joint j = make_bushing(0, 1, {0.5, 0.0, 0.1}, {-0.5, -0.2, 0.0}, {300, 200, 100, 0.3, 0.5, 0.7});
  j.frame1 = {std::cos(0.3), 0.0, std::sin(0.3), 0.0};
  j.frame2 = rest_frame2(model, j);
  j.preload = {1.0, -2.0, 0.5, 0.05, 0.0, -0.03};
  model.joints.push_back(j);
  MultibodySystem sys(model);
  const Eigen::VectorXd y0 = sys.initial_state();
  const double e0 = sys.energy(0, y0).total();
  const Momentum p0 = momentum(model, sys.layout(), y0);
  double max_e = 0, max_p = 0, max_l = 0, max_angle = 0;
  integrate_rk4(sys, 3.0, 30000, [&](double t, const Eigen::VectorXd& y) {
    max_e = std::max(max_e, std::abs(sys.energy(t, y).total() - e0) / std::abs(e0));
    const Momentum p = momentum(model, sys.layout(), y);
    max_p = std::max(max_p, (p.linear - p0.linear).norm());
    max_l = std::max(max_l, (p.angular - p0.angular).norm() / p0.angular.norm());
    const Eigen::Vector4d rel = quat_multiply(quat_conjugate(y.segment<4>(sys.layout().orientation(0))),
                                              y.segment<4>(sys.layout().orientation(1)));
    max_angle = std::max(max_angle, 2 * std::acos(std::min(1.0, std::abs(rel[0]))));
  });
  INFO("energy " << max_e << ", linear momentum " << max_p << ", angular momentum " << max_l << ", max rotation "
                 << max_angle);
  CHECK(max_angle > 1.0);  // large relative rotations were exercised
  CHECK(max_e < 1e-8);
  CHECK(max_p < 1e-12);
  CHECK(max_l < 1e-10);
}

TEST_CASE("elastic spring pendulum and a nonlinear table bushing conserve energy", "[graph][conservation]") {
  Model model;
  model.gravity = {0, -9.81, 0};
  Body bob = make_body("bob", 1.0, {0.01, 0.01, 0.01}, {0.6, -0.8, 0.1});
  bob.velocity = {0.0, 0.0, 1.0};
  model.bodies.push_back(bob);
  Body b2 = make_body("b2", 0.5, {0.01, 0.02, 0.015}, {0.6, -1.3, 0.1});
  b2.angular_velocity = {1.0, -2.0, 0.5};
  model.bodies.push_back(b2);
  Joint s;
  s.type = JointType::spring;
  s.body1 = ground;
  s.body2 = 0;
  s.point2 = {0.0, 0.05, 0.0};
  s.stiffness.set(0, 200.0);
  s.rest_length = 0.9;
  model.joints.push_back(s);
  Joint t = make_bushing(0, 1, {0, -0.25, 0}, {0, 0.25, 0}, {500, 0, 500, 1, 2, 3});
  t.tables[1] = ForceTable{{-0.1, -0.02, 0.0, 0.02, 0.1}, {-60.0, -4.0, 0.0, 4.0, 60.0}};  // hardening
  t.tables[4] = ForceTable{{-1.0, 0.0, 1.0}, {-1.0, 0.0, 3.0}};
  model.joints.push_back(t);
  MultibodySystem sys(model);
  const double e0 = sys.energy(0, sys.initial_state()).total();
  double max_e = 0;
  integrate_rk4(sys, 2.0, 40000, [&](double tt, const Eigen::VectorXd& y) {
    max_e = std::max(max_e, std::abs(sys.energy(tt, y).total() - e0) / std::abs(e0));
  });
  INFO("energy drift " << max_e);
  CHECK(max_e < 1e-7);
}

TEST_CASE("undamped chain conserves energy to the order of RK4", "[graph][conservation]") {
  ChainParams p;
  p.bodies = 8;
  p.stiffness = 1e4;
  p.damping_ratio = 0.0;
  MultibodySystem sys(make_chain(p));
  const double e0 = sys.energy(0, sys.initial_state()).total();
  std::vector<double> steps, errors;
  for (long n : {2000, 4000, 8000}) {
    double max_e = 0.0, max_kinetic = 0.0;
    integrate_rk4(sys, 0.5, n, [&](double t, const Eigen::VectorXd& y) {
      const Energy e = sys.energy(t, y);
      max_e = std::max(max_e, std::abs(e.total() - e0));
      max_kinetic = std::max(max_kinetic, e.kinetic);
    });
    steps.push_back(0.5 / static_cast<double>(n));
    errors.push_back(max_e / max_kinetic);
  }
  const double slope = log_log_slope(steps, errors);
  INFO("relative energy errors " << errors[0] << ", " << errors[1] << ", " << errors[2] << "; slope " << slope);
  CHECK(errors[2] < 1e-6);
  CHECK(slope > 3.8);
}
