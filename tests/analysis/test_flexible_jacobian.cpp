// The analytic Jacobian of models with flexible bodies against central differences: the
// frame's and the modes' rates through M(eta) and the inertia coupling, the wrenches at the
// nodes (bushings, springs, a compliant joint, loads, a damping load) through the nodes'
// motion, the bodies joined to nodes, two parts joined node to node, rigid joints at a part
// and a rigid cluster reading its modes; an implicit run with it.
#include <catch2/catch.hpp>

#include "analysis/flexible_part.hpp"
#include "graph/jacobian_check.hpp"
#include "runtime/reference_run.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::bar_part;
using test::flexible_model;

namespace {

Vec3 at(const Model& m, int body) { return m.bodies[static_cast<std::size_t>(body)].position; }

Vec3 minus(Vec3 a, Vec3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

int add_body(Model& m, const char* name, double mass, Vec3 position) {
  m.bodies.push_back(test::make_body(name, mass, {0.02 * mass, 0.03 * mass, 0.025 * mass, 0.001, 0, -0.002}, position));
  return static_cast<int>(m.bodies.size()) - 1;
}

// The lattice bar hung from the ground by a bushing at its first node, modal damping;
// rigid body R on a bushing at node 24 (frames turned), S on a compliant revolute joint at
// node 3, a spring from the frame to a driven body D; gravity, a load at node 2 (world,
// with damping against the node's motion), a load on the frame (body axes).
Model bar_on_joints() {
  Model m = flexible_model(bar_part(4, {1, 2, 3, 24}));
  m.gravity = {0.3, -9.81, 0.2};
  FlexibleBody& f = m.flexible.front();
  f.damping = 0.04 * f.data->omega2.cwiseSqrt();
  const std::vector<int> node = f.nodes;
  const int frame = f.frame;
  Joint hang = test::make_bushing(ground, node[0], at(m, node[0]), {}, {4e4, 5e4, 6e4, 40, 50, 60}, {20, 20, 20, 0.1, 0.1, 0.1});
  hang.frame1 = {std::cos(0.2), std::sin(0.2), 0.0, 0.0};
  m.joints.push_back(hang);
  const int r = add_body(m, "R", 1.5, {1.2, 0.1, 0.1});
  Joint b = test::make_bushing(node[3], r, {}, minus(at(m, r), at(m, node[3])), {3e3, 4e3, 5e3, 5, 6, 7}, {2, 2, 2, 0.01, 0.01, 0.01});
  b.frame1 = {std::cos(0.3), 0.0, std::sin(0.3), 0.0};
  b.frame2 = {std::cos(-0.1), 0.0, 0.0, std::sin(-0.1)};
  b.preload = {1, -2, 3, 0.1, -0.2, 0.3};
  m.joints.push_back(b);
  const int s = add_body(m, "S", 0.7, {0.0, 0.0, -0.3});
  Joint hinge = test::make_joint(JointType::revolute, node[2], s, {}, minus(at(m, s), at(m, node[2])));
  hinge.rigid = false;
  hinge.stiffness = {2e4, 2e4, 2e4, 30, 30, 0};
  hinge.damping = {5, 5, 5, 0.05, 0.05, 0};
  m.joints.push_back(hinge);
  const int d = add_body(m, "D", 2.0, {0.5, 0.4, 0.0});
  Joint spring = test::make_joint(JointType::spring, frame, d, {0.1, 0.05, 0.0}, {0.0, -0.05, 0.02});
  spring.stiffness = {5e3, 0, 0, 0, 0, 0};
  spring.damping = {4, 0, 0, 0, 0, 0};
  spring.rest_length = 0.3;
  m.joints.push_back(spring);
  Driver drive;
  drive.body = d;
  drive.velocity = {0.1, 0, 0};
  drive.displacement[1] = TimeFunction::harmonic(0.01, 3.0);
  m.drivers.push_back(drive);
  Load pushed;
  pushed.body = node[1];
  pushed.force = {3, -4, 5};
  pushed.torque = {0.2, 0.1, -0.3};
  pushed.point = {0.05, 0.02, -0.01};
  pushed.function = TimeFunction::harmonic(1.0, 2.0, 0.3);
  pushed.damping = {2, 3, 4};
  pushed.angular_damping = {0.1, 0.2, 0.3, 0.01, 0, 0};
  m.loads.push_back(pushed);
  Load turned;
  turned.body = frame;
  turned.force = {-2, 1, 0.5};
  turned.torque = {0.05, -0.1, 0.2};
  turned.point = {0.2, -0.1, 0.1};
  turned.body_frame = true;
  m.loads.push_back(turned);
  for (std::size_t j = 0; j < m.joints.size(); ++j) m.joints[j].name = "j" + std::to_string(j);
  return m;
}

// bar_on_joints with S held by a rigid revolute joint at node 3 (on its axis): the bar in
// a rigid cluster.
Model with_rigid_hinge(Model m) {
  Joint& hinge = m.joints[2];
  hinge.rigid = true;
  hinge.point2 = minus(at(m, m.flexible.front().nodes[2]), at(m, hinge.body2));
  return m;
}

// The analytic Jacobian against central differences at three shaken states (modes and
// their rates shaken too); entries relative to their row's largest.
void check_against_differences(MultibodySystem& sys, double bound) {
  std::string why;
  REQUIRE(sys.has_analytic_jacobian(&why));
  for (unsigned seed : {1u, 2u, 3u}) {
    const double t = 0.1 * seed;
    const Eigen::VectorXd y = test::shaken_state(sys, seed);
    Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
    sys.jacobian(t, y, jac);
    const Eigen::MatrixXd exact = Eigen::MatrixXd(jac), fd = test::central_differences(sys, t, y);
    const double worst = test::largest_row_difference(exact, fd);
    INFO("seed " << seed << ": largest difference " << worst << " of the row's largest entry");
    CHECK(worst < bound);
    // The modes' rows are there to be matched: their stiffness entries, and the frame's
    // angular velocity rows reading the modal rates (the inertia coupling).
    const StateLayout& l = sys.layout();
    const Eigen::Index tail = l.tail(0);
    const int ne = sys.model().flexible.front().data->modes();
    CHECK(fd.block(tail + ne, tail, ne, ne).cwiseAbs().maxCoeff() > 1e3);
    CHECK(fd.block(l.angular_velocity(sys.model().flexible.front().frame), tail + ne, 3, ne).cwiseAbs().maxCoeff() > 1e-3);
  }
}

}  // namespace

TEST_CASE("the analytic Jacobian of a flexible body on joints matches central differences", "[analysis][flexible][jacobian]") {
  MultibodySystem sys(bar_on_joints());
  check_against_differences(sys, 1e-6);
}

TEST_CASE("the analytic Jacobian of a free flexible body in free motion matches central differences", "[analysis][flexible][jacobian]") {
  // No joint: the frame's and the modes' rates read nothing else, every entry is inertia
  // coupling (and gravity's share on the deformation). With 26 modes the derivatives are
  // more than the 64 dual numbers keep on the stack (flexible_jacobian.cpp).
  for (int kept : {6, 20}) {
    Model m = flexible_model(bar_part(kept, {1, 2, 3, 24}));
    m.gravity = {0.0, 0.0, -9.81};
    MultibodySystem sys(m);
    INFO(sys.model().flexible.front().data->modes() << " modes");
    check_against_differences(sys, 1e-6);
  }
}

TEST_CASE("the analytic Jacobian of two flexible bodies joined node to node matches central differences",
          "[analysis][flexible][jacobian]") {
  // Bar a hung from the ground at its node 1, bar b on a bushing from a's node 24 to its
  // own node 1: a's modes read b's frame and modes and the other way round.
  Model a = flexible_model(bar_part(4, {1, 2, 3, 24}));
  Model b = flexible_model(bar_part(3, {1, 2, 3, 24}));
  for (Body& body : b.bodies) body.position[0] += 1.1;
  b.flexible.front().name = "bar2";
  for (Body& body : b.bodies) body.name = "second_" + body.name;
  Model m = test::joined_models(a, b);
  m.gravity = {0.0, 0.0, -9.81};
  const FlexibleBody& fa = m.flexible[0];
  const FlexibleBody& fb = m.flexible[1];
  m.joints.push_back(test::make_bushing(ground, fa.nodes[0], at(m, fa.nodes[0]), {}, {4e4, 4e4, 4e4, 40, 40, 40}, {10, 10, 10, 0.1, 0.1, 0.1}));
  m.joints.push_back(test::make_bushing(fa.nodes[3], fb.nodes[0], {}, minus(at(m, fa.nodes[3]), at(m, fb.nodes[0])),
                                        {2e4, 3e4, 4e4, 20, 30, 40}, {5, 5, 5, 0.05, 0.05, 0.05}));
  MultibodySystem sys(m);
  check_against_differences(sys, 1e-6);
}

TEST_CASE("the analytic Jacobian of a flexible body held by rigid joints matches central differences", "[analysis][flexible][jacobian]") {
  // The cluster is solved in generalised velocities (flexible_joints.cpp): its rates'
  // derivatives through the multipliers' (flexible_cluster_jacobian.cpp).
  SECTION("a rigid revolute joint from a node to a rigid body") {
    MultibodySystem sys(with_rigid_hinge(bar_on_joints()));
    REQUIRE(sys.clusters() == 1);
    check_against_differences(sys, 1e-7);
  }
  SECTION("a driven body holding the frame by a rigid spherical joint") {
    Model m = bar_on_joints();
    const FlexibleBody& f = m.flexible.front();
    const int d = m.drivers.front().body;
    m.joints[3] = test::make_joint(JointType::spherical, f.frame, d, minus(at(m, d), at(m, f.frame)), {});
    MultibodySystem sys(m);
    REQUIRE(sys.clusters() == 1);
    check_against_differences(sys, 1e-7);
  }
  SECTION("a rigid spherical joint from the ground to a node, and a rigid joint at the frame") {
    Model m = bar_on_joints();
    const FlexibleBody& f = m.flexible.front();
    m.joints[0] = test::make_joint(JointType::spherical, ground, f.nodes[0], at(m, f.nodes[0]), {});
    const int p = add_body(m, "P", 1.2, {0.5, -0.3, 0.0});
    m.joints.push_back(test::make_joint(JointType::revolute, f.frame, p, minus(at(m, p), at(m, f.frame)), {}));
    MultibodySystem sys(m);
    REQUIRE(sys.clusters() == 1);
    check_against_differences(sys, 1e-7);
  }
  SECTION("a rigid cluster on a bushing at a node") {
    // R and Q on a revolute joint: a cluster of rigid bodies that reads the bar's modes.
    Model m = bar_on_joints();
    const int r = 5;  // body R, on a bushing at node 24
    REQUIRE(m.bodies[static_cast<std::size_t>(r)].name == "R");
    const int q = add_body(m, "Q", 1.0, {1.4, 0.1, 0.1});
    m.joints.push_back(test::make_joint(JointType::revolute, r, q, {0.1, 0, 0}, {-0.1, 0, 0}));
    MultibodySystem sys(m);
    REQUIRE(sys.clusters() == 1);
    check_against_differences(sys, 1e-7);
  }
}

TEST_CASE("the analytic Jacobian of a rigid cluster joined to a flexible body's frame matches central differences",
          "[analysis][flexible][jacobian]") {
  // P and Q on a revolute joint (a rigid cluster), P on a bushing at the bar's frame: the
  // cluster's reactions read the frame as any body, the frame's rates read P.
  Model m = bar_on_joints();
  const int frame = m.flexible.front().frame;
  const int p = add_body(m, "P", 1.2, {0.5, -0.3, 0.0});
  const int q = add_body(m, "Q", 0.8, {0.7, -0.3, 0.0});
  m.joints.push_back(test::make_bushing(frame, p, minus(at(m, p), at(m, frame)), {}, {3e3, 3e3, 3e3, 5, 5, 5}, {1, 1, 1, 0.01, 0.01, 0.01}));
  m.joints.push_back(test::make_joint(JointType::revolute, p, q, {0.1, 0, 0}, {-0.1, 0, 0}));
  MultibodySystem sys(m);
  REQUIRE(sys.clusters() == 1);
  check_against_differences(sys, 1e-5);
}

TEST_CASE("tirk on a flexible body with the analytic Jacobian matches the differenced one and DOPRI5, with fewer evaluations",
          "[analysis][flexible][jacobian][implicit]") {
  const bool rigid = GENERATE(false, true);
  const Model m = rigid ? with_rigid_hinge(bar_on_joints()) : bar_on_joints();
  INFO((rigid ? "a rigid hinge at node 3" : "compliant joints"));
  MultibodySystem sys(m);
  RunOptions o = options_from_model(m);
  const test::MemorySink reference = test::dopri5_reference(sys, o);
  std::vector<test::MemorySink> runs(2);
  std::vector<RunSummary> summaries;
  for (const char* jacobian : {"auto", "differences"}) {
    o.jacobian = jacobian;
    summaries.push_back(run_simulation(sys, o, &runs[summaries.size()]));
  }
  for (const RunSummary& s : summaries) {
    INFO(s.steps << " steps, " << s.jacobians << " Jacobians, " << s.evaluations << " evaluations");
    CHECK(s.jacobians > 0);
  }
  // The differences spend right-hand sides on every Jacobian's coloured columns; the
  // analytic Jacobian none.
  CHECK(summaries[0].evaluations < summaries[1].evaluations);
  const Eigen::Index tail = sys.layout().tail(0), modes = sys.layout().extra;
  REQUIRE(runs[0].states.size() == reference.states.size());
  REQUIRE(runs[1].states.size() == reference.states.size());
  double gap = 0.0, modal = 0.0, deformation = 0.0;
  for (std::size_t k = 0; k < reference.states.size(); ++k)
    for (const test::MemorySink& run : runs) {
      gap = std::max(gap, test::position_gap(sys, run.states[k], reference.states[k]));
      modal = std::max(modal, (run.states[k].segment(tail, modes / 2) - reference.states[k].segment(tail, modes / 2)).cwiseAbs().maxCoeff());
      deformation = std::max(deformation, reference.states[k].segment(tail, modes / 2).cwiseAbs().maxCoeff());
    }
  CHECK(deformation > 1e-5);  // the bar deforms under its joints
  CHECK(gap < 1e-5);
  CHECK(modal < 1e-3 * deformation);
}
