// The analytic Jacobian of the multibody right-hand side against central differences, for
// every element it covers (bushings with frames, tables, preload and damping at small and
// large rotations, springs, joints to ground, loads in either frame with time functions,
// a driven body, gravity, the gyroscopic terms, compliant kinematic joints of every type
// with motors and limit stops, rigid joints of every type through their cluster's
// reactions), and its refusal where it has none.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <numbers>
#include <random>

#include "jacobian_check.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::central_differences;
using test::shaken_state;

namespace {

struct Pulling final : ForceElement {
  std::vector<int> bodies() const override { return {0}; }
  void evaluate(double, const Kinematics& k, std::span<Wrench> out) const override { out[0].force = -k.position(0); }
};

ForceTable table(double k1, double k2) {
  ForceTable t;
  t.deflection = {-1.0, -0.02, 0.0, 0.02, 1.0};
  t.force = {-0.02 * k1 - 0.98 * k2, -0.02 * k1, 0.0, 0.02 * k1, 0.02 * k1 + 0.98 * k2};
  return t;
}

// Six bodies of unequal inertia: a bushing to ground with a rotated frame, bushings between
// bodies (tables, preload, damping), a spring, a driven body, and loads.
Model jacobian_model() {
  Model m;
  m.gravity = {0.3, -9.81, 0.1};
  for (int i = 0; i < 6; ++i) {
    Body b = test::make_body("b", 1.0 + 0.3 * i, {0.02 + 0.01 * i, 0.03, 0.05, 0.002, -0.001, 0.003}, {0.6 * i, 0.05 * i, 0.0});
    b.name += std::to_string(i);
    m.bodies.push_back(b);
  }
  Joint g = test::make_bushing(ground, 0, {0, 0, 0}, {-0.3, 0, 0}, {2e4, 3e4, 4e4, 50, 60, 70}, {5, 6, 7, 0.1, 0.2, 0.3});
  g.frame1 = {std::cos(0.2), std::sin(0.2), 0.0, 0.0};
  m.joints.push_back(g);
  Joint b1 = test::make_bushing(0, 1, {0.3, 0, 0}, {-0.3, 0, 0}, {1e4, 2e4, 3e4, 40, 30, 20}, {1, 2, 3, 0.05, 0.04, 0.03});
  b1.frame1 = {std::cos(0.3), 0.0, std::sin(0.3), 0.0};
  b1.frame2 = {std::cos(-0.1), 0.0, 0.0, std::sin(-0.1)};
  b1.tables[1] = table(2e4, 5e3);
  b1.tables[4] = table(30, 90);
  b1.preload = {1, -2, 3, 0.1, -0.2, 0.3};
  m.joints.push_back(b1);
  m.joints.push_back(test::make_bushing(1, 2, {0.3, 0.02, 0}, {-0.3, 0, 0.01}, {3e4, 3e4, 3e4, 80, 80, 80}, {2, 2, 2, 0.1, 0.1, 0.1}));
  Joint spring = test::make_joint(JointType::spring, 2, 3, {0.3, 0.1, 0}, {-0.3, 0, 0.05});
  spring.stiffness = {5e3, 0, 0, 0, 0, 0};
  spring.damping = {4, 0, 0, 0, 0, 0};
  spring.rest_length = 0.1;
  m.joints.push_back(spring);
  m.joints.push_back(test::make_bushing(3, 4, {0.3, 0, 0}, {-0.3, 0, 0}, {1e4, 1e4, 1e4, 20, 20, 20}, {1, 1, 1, 0.01, 0.01, 0.01}));
  m.joints.push_back(test::make_bushing(4, 5, {0.3, 0, 0}, {-0.3, 0, 0}, {1e4, 1e4, 1e4, 20, 20, 20}));
  Driver d;
  d.body = 5;
  d.velocity = {0.2, 0, 0};
  d.displacement[1] = TimeFunction::harmonic(0.01, 3.0);
  m.drivers.push_back(d);
  Load world;
  world.body = 1;
  world.force = {3, -4, 5};
  world.torque = {0.2, 0.1, -0.3};
  world.point = {0.1, 0.2, -0.05};
  world.function = TimeFunction::harmonic(1.0, 2.0, 0.3);
  m.loads.push_back(world);
  Load body;
  body.body = 3;
  body.force = {-2, 1, 0.5};
  body.torque = {0.05, -0.1, 0.2};
  body.point = {0.2, -0.1, 0.1};
  body.body_frame = true;
  m.loads.push_back(body);
  return m;
}

}  // namespace

namespace {

// The analytic Jacobian against central differences at three shaken states: the largest
// difference, entry by entry, relative to the largest entry of its row (rows mix 1 and 1e5),
// below `bound`. A rigid cluster's rates come from a shifted solve refined twice, which
// leaves noise of about 1e-12 in them, 1e-6 in their differences: those tests use 1e-5.
void check_against_differences(MultibodySystem& sys, double bound = 1e-7) {
  REQUIRE(sys.has_analytic_jacobian());
  for (unsigned seed : {1u, 2u, 3u}) {
    const double t = 0.1 * seed;
    const Eigen::VectorXd y = shaken_state(sys, seed);
    Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
    sys.jacobian(t, y, jac);
    const Eigen::MatrixXd exact = Eigen::MatrixXd(jac), fd = central_differences(sys, t, y);
    const double worst = test::largest_row_difference(exact, fd);
    INFO("seed " << seed << ": largest difference " << worst << " of the row's largest entry");
    CHECK(worst < bound);
    CHECK(fd.cwiseAbs().maxCoeff() > 1e3);  // the stiff entries are there to be matched
  }
}

// A wrench held on a body, world frame, as Simulation::set_load holds one.
struct HeldWrench final : ForceElement {
  std::vector<int> bodies() const override { return {2}; }
  void evaluate(double, const Kinematics&, std::span<Wrench> out) const override {
    out[0] = {Eigen::Vector3d(3.0, -20.0, 5.0), Eigen::Vector3d(40.0, -7.0, 25.0)};
  }
  bool constant_wrench() const override { return true; }
};

}  // namespace

TEST_CASE("the analytic multibody Jacobian matches central differences", "[graph][jacobian]") {
  MultibodySystem sys(jacobian_model());
  check_against_differences(sys);
}

TEST_CASE("the analytic Jacobian covers force elements of constant wrench", "[graph][jacobian]") {
  // Their torque reaches the angular acceleration through the body's orientation.
  MultibodySystem sys(jacobian_model());
  sys.add_force_element(std::make_shared<HeldWrench>());
  check_against_differences(sys);
}

TEST_CASE("the analytic multibody Jacobian holds at rest, where the rotation logarithm runs its series", "[graph][jacobian]") {
  const Model m = jacobian_model();
  MultibodySystem sys(m);
  const Eigen::VectorXd y = sys.initial_state();
  Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
  sys.jacobian(0.0, y, jac);
  const Eigen::MatrixXd exact = Eigen::MatrixXd(jac), fd = central_differences(sys, 0.0, y);
  CHECK((exact - fd).cwiseAbs().maxCoeff() < 1e-6 * fd.cwiseAbs().maxCoeff());
}

namespace {

// Ten bodies in a row joined by a compliant joint of every kinematic type (each row's
// reaction -(k phi + c phi')): revolute with a position motor, spherical, prismatic with a
// velocity motor and narrow limits, cylindrical, universal, planar, fixed, a distance rod,
// a revolute joint with an effort motor and limits, and a screw.
Model compliant_joints_model() {
  Model m;
  m.gravity = {0.2, -9.81, 0.3};
  for (int i = 0; i < 10; ++i) {
    Body b = test::make_body("c", 1.0 + 0.2 * i, {0.03 + 0.01 * i, 0.04, 0.05 - 0.003 * i, 0.001, -0.002, 0.001},
                             {0.6 * i, 0.02 * i, 0.0});
    b.name += std::to_string(i);
    m.bodies.push_back(b);
  }
  const JointType types[] = {JointType::revolute, JointType::spherical, JointType::prismatic,
                             JointType::cylindrical, JointType::universal, JointType::planar,
                             JointType::fixed,    JointType::distance,  JointType::revolute,
                             JointType::screw};
  for (int k = 0; k < 10; ++k) {
    Joint j = test::make_joint(types[k], k - 1, k, {k == 0 ? -0.3 : 0.3, k == 0 ? 0.0 : 0.01, 0}, {-0.3, -0.01, 0});
    if (k == 0) j.body1 = ground;
    j.name += "_" + std::to_string(k);
    j.rigid = false;
    j.stiffness = {2e4 + 1e3 * k, 3e4, 2.5e4, 60.0 + k, 50, 40};
    j.damping = {5, 6, 7, 0.1, 0.2, 0.3};
    j.frame1 = {std::cos(0.1 * k), std::sin(0.1 * k), 0.0, 0.0};
    j.rest_length = 0.05;
    m.joints.push_back(j);
    m.joints.back().frame2 = rest_frame2(m, m.joints.back());
  }
  m.joints[0].motor.edit() = {JointMotor::Kind::position, TimeFunction::harmonic(0.3, 1.5)};
  m.joints[2].motor.edit() = {JointMotor::Kind::velocity, TimeFunction::harmonic(0.2, 2.0, 0.4)};
  m.joints[2].limits.edit() = {true, -1e-3, 1e-3, 4e4, 30};
  m.joints[8].motor.edit() = {JointMotor::Kind::effort, TimeFunction::harmonic(2.0, 1.0)};
  m.joints[8].limits.edit() = {true, -0.02, 0.02, 500, 2};
  return m;
}

}  // namespace

TEST_CASE("the analytic Jacobian covers compliant joints of every kind with their motors and limit stops",
          "[graph][jacobian]") {
  MultibodySystem sys(compliant_joints_model());
  check_against_differences(sys);
}

namespace {

// The compliant model's joints made rigid: one cluster of ten bodies hanging from
// ground, with a position motor, a velocity motor, an effort motor and limit stops; a
// stiff bushing from ground to its fifth body (the applied forces' part), and a spring
// to a free body outside (a column the cluster reads from outside).
Model rigid_joints_model() {
  Model m = compliant_joints_model();
  for (Joint& j : m.joints) j.rigid = true;
  m.simulation.assemble = true;  // the joints' points as the compliant model has them: assembled
  // Rigid, the universal joint's axes must be perpendicular and the rod must have its length.
  const Eigen::Quaterniond f2(m.joints[4].frame2[0], m.joints[4].frame2[1], m.joints[4].frame2[2], m.joints[4].frame2[3]);
  const Eigen::Quaterniond turned = f2 * Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi, Eigen::Vector3d::UnitX()));
  m.joints[4].frame2 = {turned.w(), turned.x(), turned.y(), turned.z()};
  m.joints[7].point2.set(0, m.joints[7].point2[0] - m.joints[7].rest_length);
  m.joints.push_back(test::make_bushing(ground, 4, {2.4, 0.3, 0}, {0, 0.3, 0}, {5e4, 4e4, 3e4, 90, 80, 70}, {3, 2, 1, 0.1, 0.1, 0.1}));
  Body outside = test::make_body("outside", 2.0, {0.05, 0.06, 0.07, 0, 0, 0}, {3.0, -1.0, 0.2});
  m.bodies.push_back(outside);
  Joint spring = test::make_joint(JointType::spring, 6, 10, {0.1, 0, 0}, {0, 0.1, 0});
  spring.stiffness = {3e4, 0, 0, 0, 0, 0};
  spring.damping = {20, 0, 0, 0, 0, 0};
  spring.rest_length = 0.5;
  m.joints.push_back(spring);
  return m;
}

}  // namespace

TEST_CASE("the analytic Jacobian covers rigid joints of every kind through their cluster's reactions",
          "[graph][jacobian]") {
  MultibodySystem sys(rigid_joints_model());
  REQUIRE(sys.clusters() == 1);
  REQUIRE(sys.cluster_bodies(0).size() == 10);
  check_against_differences(sys, 1e-5);
}

TEST_CASE("the analytic Jacobian of a rigid cluster holds with a driven body in it", "[graph][jacobian]") {
  // A hinge between body 4 and the driven body 5: the cluster's rows read a body whose
  // motion is prescribed, and the driven body's rates stay out of the Jacobian.
  Model m = jacobian_model();
  m.joints.push_back(test::make_joint(JointType::revolute, 4, 5, {0.3, 0, 0}, {-0.3, -0.05, 0}));
  m.joints.back().frame2 = rest_frame2(m, m.joints.back());
  MultibodySystem sys(m);
  REQUIRE(sys.clusters() == 1);
  check_against_differences(sys, 1e-5);
}

TEST_CASE("the analytic Jacobian of a rigid cluster past the dense limit, its columns solved in blocks",
          "[graph][jacobian]") {
  // A hub hinged to ground and ten bodies hinged around it (55 rows: sparse factors, past
  // the dense path's 48), one of them held by a stiff bushing: 143 columns, solved 64 at a
  // time. A star, not a chain: the shaken states of a chain of nine hinges or more left S
  // so near singular that the differences differed by half a row's largest entry, with the
  // Jacobian solved column by column as well as in blocks.
  Model m;
  m.gravity = {0.2, -9.81, 0.1};
  m.bodies.push_back(test::make_body("hub", 3.0, {0.2, 0.3, 0.25, 0.01, 0, -0.02}));
  m.joints.push_back(test::make_joint(JointType::revolute, ground, 0, {0, 0, 0}, {0, 0, 0}));
  for (int i = 1; i <= 10; ++i) {
    const double a = 0.6 * i;
    const Vec3 out{0.3 * std::cos(a), 0.3 * std::sin(a), 0.02 * i};
    Body b = test::make_body("arm", 1.0 + 0.1 * i, {0.02 + 0.002 * i, 0.03, 0.04, 0.001, 0, -0.002},
                             {2 * out[0], 2 * out[1], 2 * out[2]});
    b.name += std::to_string(i);
    m.bodies.push_back(b);
    m.joints.push_back(test::make_joint(JointType::revolute, 0, i, out, {-out[0], -out[1], -out[2]}));
    m.joints.back().frame2 = rest_frame2(m, m.joints.back());
  }
  m.joints.push_back(test::make_bushing(ground, 4, {1.0, 0.5, 0}, {0.1, 0, 0}, {5e4, 4e4, 3e4, 90, 80, 70}, {3, 2, 1, 0.1, 0.1, 0.1}));
  MultibodySystem sys(m);
  REQUIRE(sys.clusters() == 1);
  REQUIRE(sys.cluster_bodies(0).size() == 11);
  // The differences' noise grows with the arms (8e-6 with 4, 1.6e-5 with 10, the same on
  // both sides of the dense limit); a wrong column would differ by its whole size.
  check_against_differences(sys, 1e-4);
}

TEST_CASE("models without an analytic Jacobian say which item stands in the way", "[graph][jacobian]") {
  std::string why;
  SECTION("a user force element") {
    MultibodySystem sys(jacobian_model());
    sys.add_force_element(std::make_shared<Pulling>());
    CHECK_FALSE(sys.has_analytic_jacobian(&why));
    CHECK(why.find("force element") != std::string::npos);
  }
  SECTION("a submodel") {
    MultibodySystem sys(jacobian_model(), 3);
    CHECK_FALSE(sys.has_analytic_jacobian(&why));
    CHECK(why.find("submodel") != std::string::npos);
  }
}

namespace {

// A matrix of the same column starts as `wider` (`first`'s pattern and the diagonal), but
// one column's extra entry moved from the diagonal to another row on the far side of some
// of the pattern's rows: places kept from `wider` are off by one there.
Eigen::SparseMatrix<double> shifted_pattern(const Eigen::SparseMatrix<double>& first, const Eigen::SparseMatrix<double>& wider) {
  Eigen::Index column = -1, moved_to = -1;
  for (Eigen::Index c = 0; c < first.cols() && column < 0; ++c) {
    if (first.coeff(c, c) != 0 || Eigen::SparseMatrix<double>(first.col(c)).nonZeros() == 0) continue;
    for (Eigen::Index r : {Eigen::Index(0), first.rows() - 1}) {
      bool held = false, between = false;
      for (Eigen::SparseMatrix<double>::InnerIterator it(first, c); it; ++it) {
        held = held || it.row() == r;
        between = between || (it.row() - r) * (it.row() - c) < 0;
      }
      if (!held && r != c && between) {
        column = c;
        moved_to = r;
        break;
      }
    }
  }
  REQUIRE(column >= 0);
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index c = 0; c < wider.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(wider, c); it; ++it)
      entries.emplace_back(c == column && it.row() == column ? moved_to : it.row(), c, 1.0);
  Eigen::SparseMatrix<double> shifted(wider.rows(), wider.cols());
  shifted.setFromTriplets(entries.begin(), entries.end());
  shifted.makeCompressed();
  REQUIRE(std::equal(shifted.outerIndexPtr(), shifted.outerIndexPtr() + shifted.cols() + 1, wider.outerIndexPtr()));
  return shifted;
}

}  // namespace

TEST_CASE("the analytic Jacobian fills matrices of another pattern right after the first", "[graph][jacobian]") {
  // jacobian() keeps where its writes landed in the first matrix and checks them in every
  // later one: a matrix with extra entries (the diagonal added), then the pattern again,
  // must get the same numbers where the pattern has entries and zeros elsewhere.
  MultibodySystem sys(jacobian_model());
  const Eigen::VectorXd y = shaken_state(sys, 4);
  Eigen::SparseMatrix<double> first = sys.jacobian_pattern();
  sys.jacobian(0.2, y, first);
  Eigen::SparseMatrix<double> identity(first.rows(), first.cols());
  identity.setIdentity();
  Eigen::SparseMatrix<double> wider = first + identity;  // the pattern's entries and the diagonal
  wider.makeCompressed();
  REQUIRE(wider.nonZeros() > first.nonZeros());
  sys.jacobian(0.2, y, wider);
  const Eigen::MatrixXd expected(first);
  CHECK((Eigen::MatrixXd(wider) - expected).cwiseAbs().maxCoeff() == 0.0);
  // The same column starts as `wider`, but one entry moved: the checks must notice.
  Eigen::SparseMatrix<double> shifted = shifted_pattern(first, wider);
  sys.jacobian(0.2, y, shifted);
  CHECK((Eigen::MatrixXd(shifted) - expected).cwiseAbs().maxCoeff() == 0.0);
  Eigen::SparseMatrix<double> again = sys.jacobian_pattern();
  sys.jacobian(0.2, y, again);
  CHECK((Eigen::MatrixXd(again) - expected).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("the analytic Jacobian without velocity columns keeps the positions' columns exactly", "[graph][jacobian]") {
  // velocity_columns = false differentiates the joints by their bodies' positions and
  // orientations alone (the equilibrium's stiffness): those columns, the first 7 per body,
  // must be the full Jacobian's to the last bit, at rest and moving, through a rigid
  // cluster's reactions too.
  for (Model m : {jacobian_model(), compliant_joints_model(), rigid_joints_model()}) {
    MultibodySystem sys(m);
    const Eigen::Index positions = 7 * sys.layout().bodies;
    for (unsigned seed : {5u, 6u}) {
      const Eigen::VectorXd y = shaken_state(sys, seed);
      Eigen::SparseMatrix<double> full = sys.jacobian_pattern(), stiffness = sys.jacobian_pattern();
      sys.jacobian(0.3, y, full);
      sys.jacobian(0.3, y, stiffness, nullptr, false);
      const Eigen::MatrixXd a = Eigen::MatrixXd(full).leftCols(positions), b = Eigen::MatrixXd(stiffness).leftCols(positions);
      REQUIRE(a.cwiseAbs().maxCoeff() > 1e3);
      CHECK((a - b).cwiseAbs().maxCoeff() == 0.0);
    }
  }
}

TEST_CASE("the analytic Jacobian split over threads is the serial one to the last bit", "[graph][jacobian]") {
  // With a parallel loop, the joints' derivatives and (once a first call has kept where
  // each body's writes land) the bodies' rows are split: here one item at a time, in
  // reverse order. Every split must give the serial numbers, also where the kept places do
  // not fit a matrix of the same column starts (the rows are then written afresh).
  const MultibodySystem::ParallelFor reversed = [](std::size_t count, const std::function<void(std::size_t, std::size_t)>& body) {
    for (std::size_t b = count; b-- > 0;) body(b, b + 1);
  };
  MultibodySystem sys(jacobian_model());
  const Eigen::VectorXd y = shaken_state(sys, 7);
  Eigen::SparseMatrix<double> first = sys.jacobian_pattern();
  sys.jacobian(0.2, y, first);
  const Eigen::MatrixXd expected(first);
  for (int call = 0; call < 2; ++call) {  // the first keeps the places, the second replays them split
    Eigen::SparseMatrix<double> split = sys.jacobian_pattern();
    sys.jacobian(0.2, y, split, reversed);
    CHECK((Eigen::MatrixXd(split) - expected).cwiseAbs().maxCoeff() == 0.0);
  }
  Eigen::SparseMatrix<double> identity(first.rows(), first.cols());
  identity.setIdentity();
  Eigen::SparseMatrix<double> wider = first + identity;
  wider.makeCompressed();
  sys.jacobian(0.2, y, wider, reversed);  // new column starts: serial, keeping the places
  CHECK((Eigen::MatrixXd(wider) - expected).cwiseAbs().maxCoeff() == 0.0);
  Eigen::SparseMatrix<double> shifted = shifted_pattern(first, wider);
  sys.jacobian(0.2, y, shifted, reversed);  // the same column starts: split, and a place does not fit
  CHECK((Eigen::MatrixXd(shifted) - expected).cwiseAbs().maxCoeff() == 0.0);
  Eigen::SparseMatrix<double> again = sys.jacobian_pattern();
  sys.jacobian(0.2, y, again, reversed);
  CHECK((Eigen::MatrixXd(again) - expected).cwiseAbs().maxCoeff() == 0.0);
}
