// Copies of a MultibodySystem share what the model compiles to (a million-body system's
// writer copy would otherwise double it) and keep their own workspace: copies evaluate
// bit for bit as the original, on threads of their own at once, and a force element added
// to one copy is its own.
#include <catch2/catch.hpp>
#include <thread>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"

using namespace mbsflow;

namespace {

struct Tether final : ForceElement {
  int a, b;
  Tether(int a_, int b_) : a(a_), b(b_) {}
  std::vector<int> bodies() const override { return {a, b}; }
  void evaluate(double, const Kinematics& k, std::span<Wrench> out) const override {
    const Eigen::Vector3d d = k.position(b) - k.position(a);
    out[0].force = 30.0 * d;
    out[1].force = -30.0 * d;
  }
};

Model grid() {
  GridParams p;
  p.rows = 6;
  p.cols = 7;
  return make_grid(p);
}

// Derivatives at n states along a path away from the initial one.
std::vector<Eigen::VectorXd> evaluations(MultibodySystem& sys, int n) {
  std::vector<Eigen::VectorXd> out;
  Eigen::VectorXd y = sys.initial_state(), dydt(sys.dimension());
  for (int i = 0; i < n; ++i) {
    sys.rhs(0.01 * i, y, dydt);
    out.push_back(dydt);
    y += 1e-4 * dydt;
  }
  return out;
}

}  // namespace

TEST_CASE("copies of a system evaluate bit for bit as the original on threads of their own", "[graph]") {
  MultibodySystem original(grid());
  original.add_force_element(std::make_shared<Tether>(0, 40));
  MultibodySystem reference = original;  // evaluated alone first
  const std::vector<Eigen::VectorXd> expected = evaluations(reference, 50);
  MultibodySystem a = original, b = original;
  std::vector<Eigen::VectorXd> from_a, from_b;
  std::thread ta([&] { from_a = evaluations(a, 50); });
  std::thread tb([&] { from_b = evaluations(b, 50); });
  const std::vector<Eigen::VectorXd> from_original = evaluations(original, 50);
  ta.join();
  tb.join();
  // The copies hold the compiled model once: the same block, counted the same.
  CHECK(a.memory_use().compiled == original.memory_use().compiled);
  CHECK(a.memory_use().workspace > 0);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(from_a[i] == expected[i]);
    CHECK(from_b[i] == expected[i]);
    CHECK(from_original[i] == expected[i]);
  }
}

TEST_CASE("a force element added to a copy of a system stays its own", "[graph]") {
  MultibodySystem original(grid());
  const std::vector<Eigen::VectorXd> before = evaluations(original, 3);
  MultibodySystem copy = original;
  copy.add_force_element(std::make_shared<Tether>(3, 30));
  const std::vector<Eigen::VectorXd> tethered = evaluations(copy, 3);
  const std::vector<Eigen::VectorXd> after = evaluations(original, 3);
  for (std::size_t i = 0; i < before.size(); ++i) CHECK(after[i] == before[i]);
  CHECK(tethered[1] != before[1]);
  // The same element on a fresh system: the copy's derivatives, bit for bit.
  MultibodySystem fresh(grid());
  fresh.add_force_element(std::make_shared<Tether>(3, 30));
  CHECK(evaluations(fresh, 3) == tethered);
}

TEST_CASE("a system makes its workspace at its first evaluation: built and copied unevaluated, it holds none", "[graph]") {
  const Model m = grid();
  MultibodySystem unevaluated(m);
  const std::size_t bodies = m.bodies.size();
  const auto per_body = [&](const MultibodySystem& s) { return static_cast<double>(s.memory_use().workspace) / bodies; };
  CHECK(per_body(unevaluated) < 40.0);  // motor efforts, 8 bytes a joint
  MultibodySystem copy = unevaluated;
  CHECK(per_body(copy) < 40.0);
  MultibodySystem evaluated(m);
  const std::vector<Eigen::VectorXd> reference = evaluations(evaluated, 3);
  CHECK(per_body(evaluated) > 200.0);  // kinematics and joint wrenches
  CHECK(evaluations(copy, 3) == reference);
  CHECK(per_body(copy) == per_body(evaluated));
  CHECK(per_body(unevaluated) < 40.0);  // the copy's workspace is its own
  // Energy and joint wrenches need no evaluation before them.
  MultibodySystem fresh(m);
  const Eigen::VectorXd y = fresh.initial_state();
  CHECK(fresh.energy(0.0, y).kinetic == evaluated.energy(0.0, y).kinetic);
  MultibodySystem fresh2(m);
  Eigen::VectorXd a, b;
  fresh2.joint_wrenches(0.0, y, a);
  evaluated.joint_wrenches(0.0, y, b);
  CHECK(a == b);
}

TEST_CASE("a system that only computes energies makes no workspace", "[graph]") {
  // The results writer's copy computes energies. Without drivers, force elements and
  // kinematic joints they come from the state alone; the kinematics (104 bytes a body:
  // the grid's bushings read no stored rotation matrix) and the joints' wrenches (72 bytes
  // a joint, two joints a body on the grid) come with the first evaluation.
  const Model m = grid();
  MultibodySystem sys(m);
  const Eigen::VectorXd y = sys.initial_state();
  const Energy e = sys.energy(0.0, y);
  const std::size_t after_energy = sys.memory_use().workspace;
  CHECK(static_cast<double>(after_energy) / static_cast<double>(m.bodies.size()) < 40.0);
  Eigen::VectorXd dydt(sys.dimension());
  sys.rhs(0.0, y, dydt);
  CHECK(sys.memory_use().workspace >= after_energy + 104 * m.bodies.size() + 72 * m.joints.size());
  CHECK(sys.energy(0.0, y).elastic == e.elastic);
}

TEST_CASE("energies from the state alone are bit for bit those through an evaluation's kinematics", "[graph]") {
  // The same grid with a force element that stores no energy takes the kinematics' way.
  Model plain = grid();
  plain.joints[3].type = JointType::spring;  // one spring among the bushings
  plain.joints[3].rest_length = 0.07;
  Model with_element = plain;
  with_element.force_elements.push_back(std::make_shared<Tether>(2, 9));
  MultibodySystem a(plain), b(with_element);
  Eigen::VectorXd y = a.initial_state();
  // Turned, moved and moving bodies: every rotation matrix and deflection non-trivial.
  const StateLayout& l = a.layout();
  for (Eigen::Index i = 0; i < l.bodies; ++i) {
    const double s = 0.1 * static_cast<double>(i + 1);
    y.segment<4>(l.orientation(i)) = Eigen::Vector4d(1.0, 0.1 * std::sin(s), 0.2 * std::cos(3 * s), 0.05 * s).normalized();
    y.segment<3>(l.position(i)) += Eigen::Vector3d(0.01 * std::sin(7 * s), 0.02 * std::cos(5 * s), 0.003 * s);
    y.segment<3>(l.velocity(i)) = Eigen::Vector3d(std::sin(s), 0.5, -s);
    y.segment<3>(l.angular_velocity(i)) = Eigen::Vector3d(0.3, std::cos(s), 2 * s);
  }
  const Energy ea = a.energy(0.25, y), eb = b.energy(0.25, y);
  CHECK(a.memory_use().workspace < b.memory_use().workspace);  // only b made the kinematics
  CHECK(ea.elastic > 0.0);
  CHECK(ea.kinetic == eb.kinetic);
  CHECK(ea.gravity == eb.gravity);
  CHECK(ea.elastic == eb.elastic);
}

TEST_CASE("a model with a kinematic joint computes its energies through the kinematics", "[graph]") {
  Model m = grid();
  m.joints[5].type = JointType::revolute;  // compliant: its energy needs the joint's geometry
  m.joints[5].rigid = false;
  MultibodySystem sys(m);
  const Eigen::VectorXd y = sys.initial_state();
  sys.energy(0.0, y);
  CHECK(sys.memory_use().workspace >= 176 * m.bodies.size());
}

TEST_CASE("what an embedding caller can get wrong throws mbsflow::Error, not a standard exception", "[graph]") {
  CHECK_THROWS_AS(MultibodySystem(std::shared_ptr<const Model>(), 0), InputError);
  MultibodySystem sys(grid());
  sys.add_force_element(std::make_shared<Tether>(3, 30));
  const Eigen::VectorXd y = sys.initial_state();
  // A user force element leaves no analytic Jacobian; asking for it anyway is a usage error.
  Eigen::SparseMatrix<double> jac;
  CHECK_THROWS_AS(sys.jacobian(0, y, jac), InputError);
}
