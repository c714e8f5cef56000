// Rigid joints at flexible bodies (graph/src/flexible_joints.cpp), on the lattice bar of
// flexible_part.hpp reduced at three nodes of one end and one of the other: the rows'
// accelerations hold the joints without any projection (the maps T and gamma of a node's
// motion), a free assembly conserves energy, momentum and angular momentum, a bar hinged
// to the ground swings with its energy kept, and the Jacobian's pattern covers the part's
// cluster, a driven body clamps a part, and two parts pin together (their modes held by
// rigid joints: test_flexible_modes.cpp).
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "flexible_part.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::bar_part;
using test::flexible_model;

namespace {

Eigen::Vector3d v3(const Vec3& v) { return {v[0], v[1], v[2]}; }

Eigen::Matrix3d rotation_at(const StateLayout& l, const Eigen::VectorXd& y, int body) {
  const Eigen::Vector4d q = y.segment<4>(l.orientation(body));
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

// Node k of the model's flexible body `which` in the world at y, from its frame and modes alone.
Eigen::Vector3d node_in_world(const MultibodySystem& sys, const Eigen::VectorXd& y, int k, std::size_t which = 0) {
  const StateLayout& l = sys.layout();
  const FlexibleBody& f = sys.model().flexible[which];
  const int ne = f.data->modes();
  const Eigen::Index tail = sys.flexible_state(which);
  const NodeMotion n = flexible_node_motion(*f.data, k, y.segment(tail, ne), y.segment(tail + ne, ne));
  return y.segment<3>(l.position(f.frame)) + rotation_at(l, y, f.frame) * n.position;
}

int add_rigid_body(Model& m, const std::string& name, double mass, const Eigen::Vector3d& at) {
  Body b;
  b.name = name;
  b.mass = mass;
  b.inertia = Vec6{0.02 * mass, 0.03 * mass, 0.04 * mass, 0.0, 0.0, 0.0};
  b.position = {at.x(), at.y(), at.z()};
  m.bodies.push_back(b);
  return static_cast<int>(m.bodies.size()) - 1;
}

// A rigid joint from body1 at the world point `at` to node body `node` (at the node).
void join_node(Model& m, const std::string& name, JointType type, int body1, int node) {
  Joint j;
  j.name = name;
  j.type = type;
  j.body1 = body1;
  j.body2 = node;
  const Vec3& p = m.bodies[static_cast<std::size_t>(node)].position;
  if (body1 == ground) {
    j.point1 = p;
  } else {
    const Vec3& c = m.bodies[static_cast<std::size_t>(body1)].position;
    j.point1 = Vec3{p[0] - c[0], p[1] - c[1], p[2] - c[2]};
  }
  m.joints.push_back(j);
}

// The bar reduced at nodes 1, 2, 3 (one end) and 24 (the other), with rigid bodies A at node 1 and B at node
// 24 on spherical joints, everything tumbling and deforming, no gravity.
Model tumbling_assembly() {
  Model m = flexible_model(bar_part(4, {1, 2, 3, 24}));
  const FlexibleBody& f = m.flexible.front();
  const int ne = f.data->modes();
  m.flexible.front().initial_eta = Eigen::VectorXd::LinSpaced(ne, 2e-4, -1e-4);
  m.flexible.front().initial_eta_rate = Eigen::VectorXd::LinSpaced(ne, 0.05, 0.01);
  m.bodies[0].velocity = {0.3, -0.1, 0.2};
  m.bodies[0].angular_velocity = {1.5, 6.0, -2.0};
  const int a = add_rigid_body(m, "A", 1.5, v3(m.bodies[static_cast<std::size_t>(f.nodes[0])].position) + Eigen::Vector3d(-0.1, 0.05, 0));
  const int b = add_rigid_body(m, "B", 0.7, v3(m.bodies[static_cast<std::size_t>(f.nodes[3])].position) + Eigen::Vector3d(0.1, 0, 0.05));
  m.bodies[static_cast<std::size_t>(b)].angular_velocity = {0.0, 0.0, 3.0};
  m.simulation.assemble = true;  // the bodies' velocities are made consistent with the joints
  join_node(m, "a", JointType::spherical, a, f.nodes[0]);
  join_node(m, "b", JointType::spherical, b, f.nodes[3]);
  return m;
}

// Where joint k (spherical, from a rigid body to node `node`) is open, by the frame and modes.
double spherical_gap(const MultibodySystem& sys, const Eigen::VectorXd& y, int k, int node) {
  const Joint& j = sys.model().joints[static_cast<std::size_t>(k)];
  const StateLayout& l = sys.layout();
  const Eigen::Vector3d on_body1 = y.segment<3>(l.position(j.body1)) + rotation_at(l, y, j.body1) * v3(j.point1.get());
  return (on_body1 - node_in_world(sys, y, node)).norm();
}

test::Momentum total_momentum(const MultibodySystem& sys, const Eigen::VectorXd& y) {
  const StateLayout& l = sys.layout();
  test::Momentum p = test::flexible_momentum(sys, y);
  for (const char* name : {"A", "B"}) {
    const auto i = static_cast<int>(std::find_if(sys.model().bodies.begin(), sys.model().bodies.end(),
                                                 [&](const Body& b) { return b.name == name; }) - sys.model().bodies.begin());
    const Body& b = sys.model().bodies[static_cast<std::size_t>(i)];
    const Eigen::Vector3d mv = b.mass * y.segment<3>(l.velocity(i));
    const Eigen::Matrix3d r = rotation_at(l, y, i);
    const Eigen::Vector3d inertia(b.inertia.get()[0], b.inertia.get()[1], b.inertia.get()[2]);
    p.linear += mv;
    p.angular += Eigen::Vector3d(y.segment<3>(l.position(i))).cross(mv) + r * inertia.cwiseProduct(y.segment<3>(l.angular_velocity(i)));
  }
  return p;
}

}  // namespace

TEST_CASE("rigid joints at a flexible body's nodes hold by their accelerations alone, without projection",
          "[analysis][flexible][joints]") {
  MultibodySystem sys(tumbling_assembly());
  REQUIRE(sys.clusters() == 1);  // both nodes' joints, the frame and the two bodies: one cluster
  Eigen::VectorXd y = sys.initial_state();
  REQUIRE(spherical_gap(sys, y, 0, 0) < 1e-10);
  REQUIRE(spherical_gap(sys, y, 1, 3) < 1e-10);
  Rk4 rk(sys.dimension());
  const int steps = 2000;
  const double h = 0.2 / steps;
  for (int k = 0; k < steps; ++k) rk.step(sys, k * h, h, y);
  // A wrong term of a node's acceleration (w x (w x x) is some 10 m/s^2 here) opens the
  // joints by about 0.1 m in 0.2 s; RK4's own drift is some 1e-11 m.
  CHECK(spherical_gap(sys, y, 0, 0) < 1e-8);
  CHECK(spherical_gap(sys, y, 1, 3) < 1e-8);
  CHECK(y.segment(sys.layout().tail(0), sys.model().flexible.front().data->modes()).norm() > 1e-5);  // it deforms
}

TEST_CASE("a free assembly of a flexible body and rigid bodies on rigid joints conserves energy, momentum and angular momentum",
          "[analysis][flexible][joints]") {
  MultibodySystem sys(tumbling_assembly());
  const Eigen::VectorXd y0 = sys.initial_state();
  const double e0 = sys.energy(0.0, y0).total();
  const test::Momentum p0 = total_momentum(sys, y0);
  struct Worst {
    double energy = 0.0, linear = 0.0, angular = 0.0, gap = 0.0;
  };
  auto run = [&](long steps) {
    Worst w;
    test::integrate_rk4(sys, 0.5, steps, [&](double t, const Eigen::VectorXd& y) {
      w.energy = std::max(w.energy, std::abs(sys.energy(t, y).total() - e0));
      const test::Momentum p = total_momentum(sys, y);
      w.linear = std::max(w.linear, (p.linear - p0.linear).norm());
      w.angular = std::max(w.angular, (p.angular - p0.angular).norm());
      w.gap = std::max({w.gap, spherical_gap(sys, y, 0, 0), spherical_gap(sys, y, 1, 3)});
    });
    return w;
  };
  const Worst coarse = run(10000), fine = run(20000);
  for (const Worst& w : {coarse, fine}) {
    CHECK(w.gap < 1e-10);  // the projection after each step
    // The constraint forces are internal and the velocity projection mass-weighted:
    // the momenta are kept to rounding.
    CHECK(w.linear < 1e-10 * p0.linear.norm());
    CHECK(w.angular < 1e-9 * p0.angular.norm());
  }
  // The energy to RK4's error: at least 16 times smaller at half the step (about 30
  // measured), 1.3e-7 of it at 20000 steps.
  CHECK(fine.energy < 3e-7 * e0);
  CHECK(fine.energy * 16 < coarse.energy);
}

TEST_CASE("a flexible bar hinged at a node to the ground by a rigid revolute joint swings under gravity, its energy kept",
          "[analysis][flexible][joints]") {
  Model m = flexible_model(bar_part(4, {1, 2, 3, 24}));
  m.gravity = {0.0, -9.81, 0.0};
  join_node(m, "hinge", JointType::revolute, ground, m.flexible.front().nodes[0]);  // about the world z axis
  MultibodySystem sys(m);
  const Eigen::VectorXd y0 = sys.initial_state();
  const double e0 = sys.energy(0.0, y0).total();
  double worst = 0.0, lowest = 0.0, worst_gap = 0.0;
  const Eigen::Vector3d hinge = v3(m.bodies[static_cast<std::size_t>(m.flexible.front().nodes[0])].position);
  const Eigen::VectorXd y = test::integrate_rk4(sys, 0.5, 20000, [&](double t, const Eigen::VectorXd& y) {
    const Energy e = sys.energy(t, y);
    worst = std::max(worst, std::abs(e.total() - e0));
    lowest = std::min(lowest, e.gravity);
    worst_gap = std::max(worst_gap, (node_in_world(sys, y, 0) - hinge).norm());
  });
  CHECK(lowest < -5.0);  // it swings down: the energy exchanged is large
  CHECK(worst < 1e-7 * std::abs(lowest));
  CHECK(worst_gap < 1e-10);
  // The hinge's axis is z: the frame turns about z only.
  const Eigen::Vector3d w = rotation_at(sys.layout(), y, m.flexible.front().frame) * y.segment<3>(sys.layout().angular_velocity(0));
  CHECK(std::hypot(w.x(), w.y()) < 1e-9 * std::abs(w.z()));
}

TEST_CASE("the Jacobian pattern of a flexible body in a rigid cluster holds every non-zero of the differenced Jacobian",
          "[analysis][flexible][joints][jacobian]") {
  // Body A on a spherical joint at node 1; body C on a bushing at node 24, which no rigid
  // joint holds: A's reactions read C through the whole part's solve.
  Model m = tumbling_assembly();
  m.joints.pop_back();
  const FlexibleBody& f = m.flexible.front();
  const int c = add_rigid_body(m, "C", 0.9, v3(m.bodies[static_cast<std::size_t>(f.nodes[3])].position) + Eigen::Vector3d(0.2, 0, 0));
  Joint j = test::make_bushing(f.nodes[3], c, {0, 0, 0}, {-0.2, 0, 0}, {1e3, 2e3, 3e3, 10, 20, 30}, {1, 2, 3, 0.1, 0.2, 0.3});
  m.joints.push_back(j);
  MultibodySystem sys(m);
  const Eigen::VectorXd y = sys.initial_state();
  const test::PatternCount count = test::count_against_pattern(sys, 0.1, y, sys.jacobian_pattern());
  CHECK(count.outside == 0);
  CHECK(count.inside > 300);
}

TEST_CASE("a flexible bar clamped by a fixed joint to a driven body follows it (base excitation)", "[analysis][flexible][joints]") {
  // The shaker lifts by A (1 - cos 2 pi f t), from rest, far below the bar's modes: the bar
  // moves with it, lagging by its quasi-static deflection under the inertial load, which
  // grows as the acceleration, f^2.
  const double amplitude = 1e-3;
  struct Worst {
    double gap = 0.0, turn = 0.0, follow = 0.0;
  };
  auto shake = [&](double hz) {
    Model m = flexible_model(bar_part(4, {1, 2, 3, 24}));
    const FlexibleBody& f = m.flexible.front();
    const Eigen::Vector3d at = v3(m.bodies[static_cast<std::size_t>(f.nodes[0])].position);
    const int shaker = add_rigid_body(m, "shaker", 1.0, at);
    Driver d;
    d.body = shaker;
    d.displacement[2] = TimeFunction::harmonic(amplitude, hz, -0.5 * std::numbers::pi);
    d.displacement[2].offset = amplitude;
    m.drivers.push_back(d);
    join_node(m, "clamp", JointType::fixed, shaker, f.nodes[0]);
    MultibodySystem sys(m);
    const StateLayout& l = sys.layout();
    const Eigen::VectorXd y0 = sys.initial_state();
    Worst w;
    const double half_period = 0.5 / hz;
    test::integrate_rk4(sys, half_period, std::lround(half_period / 2.5e-5), [&](double t, const Eigen::VectorXd& y) {
      const double lift = evaluate(d.displacement[2], t).value;
      w.gap = std::max(w.gap, (node_in_world(sys, y, 0) - at - Eigen::Vector3d(0, 0, lift)).norm());
      w.turn = std::max(w.turn, (rotation_at(l, y, 0) - Eigen::Matrix3d::Identity()).norm());
      w.follow = std::max(w.follow, std::abs(y[l.position(0) + 2] - y0[l.position(0) + 2] - lift));
    });
    return w;
  };
  const Worst fast = shake(2.0), slow = shake(1.0);
  for (const Worst& w : {fast, slow}) {
    CHECK(w.gap < 1e-10);   // the clamped node on the shaker
    CHECK(w.turn < 1e-10);  // the joint's rotation rows hold the frame's turn
  }
  CHECK(fast.follow < 0.05 * amplitude);  // 2.7 % measured
  CHECK(fast.follow / slow.follow == Approx(4.0).epsilon(0.1));
}

TEST_CASE("two flexible bodies pinned together at their nodes: the joint holds by its accelerations, the momenta are kept",
          "[analysis][flexible][joints]") {
  // Bar b's node 1 on bar a's node 24 by a spherical joint; a tumbles and deforms, b starts
  // at rest: one cluster holds both parts' frames and modes.
  const ReducedPart part = bar_part(4, {1, 2, 3, 24});
  Model a = flexible_model(part), b = flexible_model(part);
  const Eigen::Vector3d shift = v3(a.bodies[static_cast<std::size_t>(a.flexible.front().nodes[3])].position) -
                                v3(b.bodies[static_cast<std::size_t>(b.flexible.front().nodes[0])].position);
  for (Body& body : b.bodies) {
    body.name = "b." + body.name;
    body.position = {body.position[0] + shift.x(), body.position[1] + shift.y(), body.position[2] + shift.z()};
  }
  b.flexible.front().name = "b";
  const int ne = part.floating.modes();
  a.flexible.front().initial_eta = Eigen::VectorXd::LinSpaced(ne, 2e-4, -1e-4);
  a.flexible.front().initial_eta_rate = Eigen::VectorXd::LinSpaced(ne, 0.05, 0.01);
  a.bodies[0].angular_velocity = {1.5, 6.0, -2.0};
  Model m = test::joined_models(a, b);
  m.simulation.assemble = true;
  join_node(m, "pin", JointType::spherical, m.flexible[0].nodes[3], m.flexible[1].nodes[0]);
  MultibodySystem sys(m);
  REQUIRE(sys.clusters() == 1);
  const auto gap = [&](const Eigen::VectorXd& y) { return (node_in_world(sys, y, 3, 0) - node_in_world(sys, y, 0, 1)).norm(); };
  const auto momentum = [&](const Eigen::VectorXd& y) {
    test::Momentum p = test::flexible_momentum(sys, y, 0);
    const test::Momentum q = test::flexible_momentum(sys, y, 1);
    p.linear += q.linear;
    p.angular += q.angular;
    return p;
  };
  Eigen::VectorXd y = sys.initial_state();
  REQUIRE(gap(y) < 1e-10);
  const test::Momentum p0 = momentum(y);
  const double e0 = sys.energy(0.0, y).total();
  Rk4 rk(sys.dimension());
  const int steps = 4000;
  const double h = 0.1 / steps;
  for (int k = 0; k < steps; ++k) rk.step(sys, k * h, h, y);
  CHECK(gap(y) < 1e-8);  // no projection
  double worst_gap = 0.0, worst_energy = 0.0, worst_angular = 0.0;
  test::integrate_rk4(sys, 0.2, 8000, [&](double t, const Eigen::VectorXd& x) {
    worst_gap = std::max(worst_gap, gap(x));
    worst_energy = std::max(worst_energy, std::abs(sys.energy(t, x).total() - e0));
    worst_angular = std::max(worst_angular, (momentum(x).angular - p0.angular).norm());
  });
  CHECK(worst_gap < 1e-10);
  CHECK(worst_angular < 1e-9 * p0.angular.norm());
  CHECK(worst_energy < 3e-7 * e0);  // RK4's error: 7e-8 measured
}
