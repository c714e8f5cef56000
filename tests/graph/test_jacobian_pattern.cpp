// The Jacobian pattern the implicit methods difference and factor by: every entry of the
// true Jacobian (dense finite differences) lies in it, for each kind of coupling between
// bodies, and it stays sparse.
#include <catch2/catch.hpp>

#include "mbsflow/graph/multibody_system.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

// Pulls the centres of two bodies together, reading both.
struct CentreSpring final : ForceElement {
  int a, b;
  CentreSpring(int a_, int b_) : a(a_), b(b_) {}
  std::vector<int> bodies() const override { return {a, b}; }
  void evaluate(double, const Kinematics& k, std::span<Wrench> out) const override {
    const Eigen::Vector3d d = k.position(b) - k.position(a) + 0.1 * (k.velocity(b) - k.velocity(a));
    out[0].force = 50.0 * d;
    out[1].force = -50.0 * d;
  }
};

// Rigid pair hung from ground, a bushing, a spring, a compliant revolute joint, a free
// spinning body tied by a force element, and an untouched body.
Model coupled_model() {
  Model m;
  m.gravity = {0, -9.81, 0};
  const Vec6 inertia{0.02, 0.03, 0.04, 0.001, 0.0, 0.002};
  for (int i = 0; i < 7; ++i) {
    Body b = test::make_body("b", 1.0 + 0.1 * i, inertia, {0.5 + i, 0.1 * i, 0.0});
    b.name += std::to_string(i);
    b.velocity = {0.1, -0.2 * i, 0.05};
    b.angular_velocity = {0.3, 0.1 * i, -0.4};
    m.bodies.push_back(b);
  }
  m.joints.push_back(test::make_joint(JointType::revolute, ground, 0, {0, 0, 0}, {-0.5, 0, 0}));
  m.joints.push_back(test::make_joint(JointType::revolute, 0, 1, {0.5, 0, 0}, {-0.5, -0.1, 0}));
  m.joints.push_back(test::make_bushing(1, 2, {0.5, 0, 0}, {-0.5, -0.1, 0}, {1e3, 2e3, 3e3, 10, 20, 30}, {1, 2, 3, 0.1, 0.2, 0.3}));
  Joint spring = test::make_joint(JointType::spring, 2, 3, {0.5, 0, 0}, {-0.5, 0, 0});
  spring.stiffness = {400, 0, 0, 0, 0, 0};
  spring.damping = {2, 0, 0, 0, 0, 0};
  spring.rest_length = 0.8;
  m.joints.push_back(spring);
  Joint hinge = test::make_joint(JointType::revolute, 3, 4, {0.5, 0, 0}, {-0.5, -0.1, 0});
  hinge.rigid = false;
  for (Joint& j : m.joints) j.frame2 = rest_frame2(m, j);
  m.joints.push_back(hinge);
  m.joints.back().frame2 = rest_frame2(m, m.joints.back());
  set_bushing_from_frequency(m, m.joints.back(), 40.0, 0.05);
  return m;
}

}  // namespace

TEST_CASE("the Jacobian pattern holds every non-zero of the finite-difference Jacobian and stays sparse", "[graph][jacobian]") {
  const Model m = coupled_model();
  MultibodySystem sys(m);
  sys.add_force_element(std::make_shared<CentreSpring>(4, 5));
  const Eigen::SparseMatrix<double> pattern = sys.jacobian_pattern();
  const Eigen::Index n = sys.dimension();
  REQUIRE(pattern.rows() == n);
  REQUIRE(pattern.cols() == n);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(pattern);
  const test::PatternCount count = test::count_against_pattern(sys, 0.3, sys.initial_state(), pattern);
  CHECK(count.outside == 0);
  CHECK(count.inside > 200);
  // Body 6 is coupled to nothing: its accelerations read only its own state.
  const StateLayout& l = sys.layout();
  for (Eigen::Index c = 0; c < n; ++c)
    if (c < l.position(6) || c >= l.position(6) + 3)
      CHECK(dense(l.velocity(6), c) == (c == l.orientation(6) || c == l.orientation(6) + 1 || c == l.orientation(6) + 2 ||
                                                c == l.orientation(6) + 3 || (c >= l.velocity(6) && c < l.velocity(6) + 3) ||
                                                (c >= l.angular_velocity(6) && c < l.angular_velocity(6) + 3)
                                            ? 1.0
                                            : 0.0));
  // Bodies 0 and 1 (one rigid cluster) read each other, and body 0 reads body 2 through
  // the cluster's reactions to the bushing on body 1, but not body 3 beyond it.
  CHECK(dense(l.velocity(0), l.position(1)) == 1.0);
  CHECK(dense(l.velocity(0), l.position(2)) == 1.0);
  CHECK(dense(l.velocity(0), l.position(3)) == 0.0);
  // The force element couples 4 and 5.
  CHECK(dense(l.velocity(5), l.velocity(4)) == 1.0);
  CHECK(pattern.nonZeros() < n * n / 3);
}
