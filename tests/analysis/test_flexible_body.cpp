// A reduced FE body on a floating frame (graph/flexible_body.hpp), on a bar-like lattice of
// point masses and axial springs reduced by Craig-Bampton at one end's four nodes: the
// inertia invariants against the lattice's mass properties, a small free vibration at
// the free part's frequency, and the conservation laws of free motion (energy, linear and
// angular momentum) with large rotation and deformation rates, and with a bushing and
// gravity acting at an interface node.
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "mbsflow/analysis/craig_bampton.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "flexible_part.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::bar_part;
using test::flexible_model;

using test::flexible_momentum;
using test::Momentum;

TEST_CASE("flexible body: the floating frame's invariants are the lattice's mass properties, its modes the free part's",
          "[analysis][flexible]") {
  const ReducedPart part = bar_part(6);
  const FloatingFrameData& d = part.floating;
  REQUIRE(d.modes() == 18 - 6);
  REQUIRE(d.node_id == std::vector<long>{1, 2, 3, 4});
  const Eigen::MatrixXd& m0 = d.mass0;
  CHECK((m0.topLeftCorner<3, 3>() - d.mass * Eigen::Matrix3d::Identity()).norm() < 1e-9 * d.mass);
  CHECK((m0.block<3, 3>(3, 3) - d.inertia).norm() < 1e-9 * d.inertia.norm());
  CHECK(m0.block<3, 3>(0, 3).norm() < 1e-9 * d.mass);  // the origin is the centre of mass
  CHECK(m0.topRightCorner(6, d.modes()).norm() < 1e-8 * d.mass);  // modes orthogonal to rigid motion
  CHECK((m0.bottomRightCorner(d.modes(), d.modes()) - Eigen::MatrixXd::Identity(d.modes(), d.modes())).norm() < 1e-9);
  const Eigen::VectorXd free = reduced_frequencies(part, false);
  for (int k = 0; k < d.modes(); ++k) CHECK(std::sqrt(d.omega2[k]) / (2 * std::numbers::pi) == Approx(free[6 + k]).epsilon(1e-8));
  // The interface nodes are where the lattice has them, from the centre of mass.
  CHECK((d.node_position[0] + d.centre - Eigen::Vector3d(0, 0, 0)).norm() < 1e-12);
  CHECK((d.node_position[3] + d.centre - Eigen::Vector3d(0, 0.1, 0.1)).norm() < 1e-12);
}

TEST_CASE("flexible body: a small free vibration keeps the free part's frequency, the frame at rest", "[analysis][flexible]") {
  const ReducedPart part = bar_part(6);
  Model m = flexible_model(part);
  const int ne = part.floating.modes();
  m.flexible.front().initial_eta = Eigen::VectorXd::Unit(ne, 0) * 1e-5;
  MultibodySystem sys(m);
  const double period = 2 * std::numbers::pi / std::sqrt(part.floating.omega2[0]);
  const Eigen::VectorXd y = test::integrate_rk4(sys, period, 4000);
  const StateLayout& l = sys.layout();
  CHECK(y[l.tail(0)] == Approx(1e-5).epsilon(1e-6));
  CHECK(y.segment(l.tail(1), ne - 1).norm() < 1e-12);
  CHECK(y.segment<3>(l.position(0)).norm() < 1e-12);
}

TEST_CASE("flexible body in free motion conserves energy, momentum and angular momentum", "[analysis][flexible]") {
  const ReducedPart part = bar_part(6);
  Model m = flexible_model(part);
  const int ne = part.floating.modes();
  FlexibleBody& f = m.flexible.front();
  f.initial_eta = Eigen::VectorXd::LinSpaced(ne, 2e-4, -1e-4);
  f.initial_eta_rate = Eigen::VectorXd::LinSpaced(ne, 0.05, 0.01);
  m.bodies[0].velocity = {0.3, -0.1, 0.2};
  m.bodies[0].angular_velocity = {1.5, 6.0, -2.0};  // a fast tumble: every coupling term works
  MultibodySystem sys(m);
  const Eigen::VectorXd y0 = sys.initial_state();
  const Energy e0 = sys.energy(0.0, y0);
  const Momentum p0 = flexible_momentum(sys, y0);
  REQUIRE(e0.elastic > 0.0);
  double worst_energy = 0.0, worst_linear = 0.0, worst_angular = 0.0;
  test::integrate_rk4(sys, 0.5, 50000, [&](double t, const Eigen::VectorXd& y) {
    worst_energy = std::max(worst_energy, std::abs(sys.energy(t, y).total() - e0.total()));
    const Momentum p = flexible_momentum(sys, y);
    worst_linear = std::max(worst_linear, (p.linear - p0.linear).norm());
    worst_angular = std::max(worst_angular, (p.angular - p0.angular).norm());
  });
  // RK4's error at this step (it falls as h^4 with the step); the momenta are conserved by
  // the equations' form, to rounding.
  CHECK(worst_energy < 1e-9 * e0.total());
  CHECK(worst_linear < 1e-12 * p0.linear.norm());
  CHECK(worst_angular < 1e-11 * p0.angular.norm());
}

TEST_CASE("flexible body held at an interface node by a bushing under gravity conserves energy", "[analysis][flexible]") {
  const ReducedPart part = bar_part(4);
  Model m = flexible_model(part);
  m.gravity = {0.0, 0.0, -9.81};
  Joint j;
  j.name = "hinge";
  j.type = JointType::bushing;
  j.body1 = ground;
  j.body2 = m.flexible.front().nodes[1];
  j.point1 = m.bodies[static_cast<std::size_t>(j.body2)].position;
  j.stiffness = {1e5, 1e5, 1e5, 0.0, 0.0, 0.0};
  m.joints.push_back(j);
  m.bodies[0].angular_velocity = {0.0, 1.0, 0.5};
  MultibodySystem sys(m);
  const Eigen::VectorXd y0 = sys.initial_state();
  const double e0 = sys.energy(0.0, y0).total();
  double worst = 0.0, lowest = 0.0;
  test::integrate_rk4(sys, 0.5, 50000, [&](double t, const Eigen::VectorXd& y) {
    const Energy e = sys.energy(t, y);
    worst = std::max(worst, std::abs(e.total() - e0));
    lowest = std::min(lowest, e.gravity);
  });
  CHECK(lowest < -1.0);  // it swings: the energy exchanged is large
  CHECK(worst < 1e-7 * std::abs(lowest));
}
