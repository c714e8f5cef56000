// Craig-Bampton reduction (analysis/craig_bampton.hpp) on a small FE-like model with a
// known answer: a braced 3 x 3 x 3 lattice of point masses joined by axial springs (a
// rigid truss), its full eigenproblem solved densely beside it. Held at its interface the
// reduced part has the full model's held frequencies; free, its frequencies bound the
// full model's from above, converge as modes are added, and equal them with every mode;
// mass, centre and inertia are the point masses' sums.
#include <catch2/catch.hpp>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "mbsflow/analysis/craig_bampton.hpp"
#include "mbsflow/error.hpp"
#include "spring_lattice.hpp"

using namespace mbsflow;

namespace {

struct Truss {
  FeMatrices fe;
  std::vector<Eigen::Vector3d> dof_position;
  std::vector<Eigen::Vector3d> node;
  std::vector<double> node_mass;
};

// Nodes 1..27 on a 0.3 m grid, masses 1 + (node % 5) kg, springs of 1e6 / length N/m
// between every two nodes at most a cube's diagonal apart.
Truss truss() {
  Truss t;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        t.node.emplace_back(0.3 * i, 0.2 * j + 0.01 * i, 0.25 * k);
        t.node_mass.push_back(1.0 + static_cast<double>(t.node.size() % 5));
      }
  test::SpringLattice lattice = test::spring_lattice(t.node, t.node_mass, 0.5, 1e6);
  t.fe = std::move(lattice.fe);
  t.dof_position = std::move(lattice.dof_position);
  return t;
}

// Frequencies (Hz, ascending) of K x = w^2 M x, dense.
Eigen::VectorXd dense_frequencies(const Eigen::MatrixXd& k, const Eigen::MatrixXd& m) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m, Eigen::EigenvaluesOnly);
  Eigen::VectorXd f = eig.eigenvalues();
  for (Eigen::Index j = 0; j < f.size(); ++j) f[j] = std::sqrt(std::max(f[j], 0.0)) / (2 * std::numbers::pi);
  return f;
}

// The model's stiffness and mass without the DOFs of nodes 1, 2, 4 (held there).
std::pair<Eigen::MatrixXd, Eigen::MatrixXd> held(const Truss& t) {
  std::vector<Eigen::Index> keep;
  for (std::size_t k = 0; k < t.fe.dofs.size(); ++k)
    if (t.fe.dofs[k].node != 1 && t.fe.dofs[k].node != 2 && t.fe.dofs[k].node != 4) keep.push_back(static_cast<Eigen::Index>(k));
  const Eigen::MatrixXd k = Eigen::MatrixXd(t.fe.stiffness), m = Eigen::MatrixXd(t.fe.mass);
  return {k(keep, keep), m(keep, keep)};
}

CraigBamptonOptions options(std::vector<long> nodes, int modes) {
  CraigBamptonOptions o;
  o.interface_nodes = std::move(nodes);
  o.modes = modes;
  return o;
}

}  // namespace

TEST_CASE("Craig-Bampton: held at its interface the reduced part has the full model's lowest held frequencies", "[analysis][reduce]") {
  const Truss t = truss();
  const auto [k_held, m_held] = held(t);
  const Eigen::VectorXd exact = dense_frequencies(k_held, m_held);
  const ReducedPart part = craig_bampton(t.fe, t.dof_position, options({1, 2, 4}, 8));
  REQUIRE(part.fixed_frequency.size() == 8);
  for (Eigen::Index j = 0; j < 8; ++j) CHECK(part.fixed_frequency[j] == Approx(exact[j]).epsilon(1e-9));
  CHECK(reduced_frequencies(part, true) == part.fixed_frequency);
  // The modal block of the reduced matrices: identity mass, diagonal stiffness (2 pi f)^2.
  const Eigen::MatrixXd mm = part.mass.bottomRightCorner(8, 8), kk = part.stiffness.bottomRightCorner(8, 8);
  CHECK((mm - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff() < 1e-10);
  for (Eigen::Index j = 0; j < 8; ++j) CHECK(std::sqrt(kk(j, j)) / (2 * std::numbers::pi) == Approx(exact[j]).epsilon(1e-9));
  // The interface DOFs first, in the order of the nodes given.
  REQUIRE(part.interface_dofs.size() == 9);
  CHECK(part.interface_dofs[0] == FeDof{1, 1});
  CHECK(part.interface_dofs[8] == FeDof{4, 3});
}

TEST_CASE("Craig-Bampton: free, the reduced part's frequencies bound the full model's from above and converge to them",
          "[analysis][reduce]") {
  const Truss t = truss();
  const Eigen::VectorXd exact = dense_frequencies(Eigen::MatrixXd(t.fe.stiffness), Eigen::MatrixXd(t.fe.mass));
  const int interior = static_cast<int>(t.fe.dofs.size()) - 9;
  double previous = INFINITY;
  for (int modes : {3, 6, 20, interior}) {
    const ReducedPart part = craig_bampton(t.fe, t.dof_position, options({1, 2, 4}, modes));
    const Eigen::VectorXd f = reduced_frequencies(part, false);
    double worst = 0;
    REQUIRE(f.size() == 9 + modes);
    for (Eigen::Index j = 6; j < 12; ++j) {  // the six lowest elastic ones, after six rigid-body motions
      INFO("mode " << j << ": " << f[j] << " Hz, exact " << exact[j]);
      CHECK(f[j] >= exact[j] * (1 - 1e-9));
      worst = std::max(worst, f[j] / exact[j] - 1);
    }
    for (Eigen::Index j = 0; j < 6; ++j) CHECK(f[j] < 1e-5 * exact[6]);
    INFO(modes << " modes: worst of the six lowest elastic frequencies " << worst);
    CHECK(worst <= previous);
    previous = worst;
  }
  CHECK(previous < 1e-9);  // every interior mode kept: the full model itself
}

TEST_CASE("Craig-Bampton: the reduced part's mass, centre and inertia are the model's", "[analysis][reduce]") {
  const Truss t = truss();
  double mass = 0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  for (std::size_t a = 0; a < t.node.size(); ++a) {
    mass += t.node_mass[a];
    first += t.node_mass[a] * t.node[a];
  }
  const Eigen::Vector3d centre = first / mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (std::size_t a = 0; a < t.node.size(); ++a) {
    const Eigen::Vector3d r = t.node[a] - centre;
    inertia += t.node_mass[a] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  const ReducedPart part = craig_bampton(t.fe, t.dof_position, options({1, 2, 4}, 4));
  CHECK(part.properties.mass == Approx(mass).epsilon(1e-14));
  CHECK((part.properties.centre - centre).norm() < 1e-14);
  CHECK((part.properties.inertia - inertia).norm() < 1e-12 * inertia.norm());
  // A rigid translation along z (every interface z DOF moved by 1) carries the whole mass,
  // and the coupling of the rigid fields with it is the mass along z.
  Eigen::VectorXd u = Eigen::VectorXd::Zero(part.mass.rows());
  for (std::size_t k = 0; k < part.interface_dofs.size(); ++k)
    if (part.interface_dofs[k].direction == 3) u[static_cast<Eigen::Index>(k)] = 1;
  CHECK(u.dot(part.mass * u) == Approx(mass).epsilon(1e-10));
  CHECK((part.stiffness * u).norm() < 1e-6 * part.stiffness.norm());
  CHECK(part.rigid_coupling.row(2).dot(u) == Approx(mass).epsilon(1e-10));
  CHECK(std::abs(part.rigid_coupling.row(0).dot(u)) < 1e-10 * mass);
}

TEST_CASE("Craig-Bampton refuses an interface that does not hold the part, unknown nodes and too many modes", "[analysis][reduce]") {
  const Truss t = truss();
  CHECK_THROWS_WITH(craig_bampton(t.fe, t.dof_position, options({1}, 4)), Catch::Contains("does not hold the part"));
  CHECK_THROWS_WITH(craig_bampton(t.fe, t.dof_position, options({1, 2, 99}, 4)), Catch::Contains("interface node 99"));
  CHECK_THROWS_WITH(craig_bampton(t.fe, t.dof_position, options({1, 2, 2}, 4)), Catch::Contains("named twice"));
  CHECK_THROWS_WITH(craig_bampton(t.fe, t.dof_position, options({1, 2, 4}, 73)), Catch::Contains("fewer fixed-interface modes"));
  CHECK_THROWS_AS(craig_bampton(t.fe, t.dof_position, options({}, 4)), InputError);
}

TEST_CASE("a face tied rigidly to a master node: the mass is kept, and held at the master the face is held", "[analysis][reduce]") {
  const Truss t = truss();
  const std::vector<long> face{1, 2, 4, 5};
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (long node : face) centre += t.node[static_cast<std::size_t>(node - 1)] / 4.0;
  const TiedModel tied = tie_rigidly(t.fe, t.dof_position, face, 100, centre);
  CHECK(tied.fe.dofs.size() == t.fe.dofs.size() - 12 + 6);
  CHECK(tied.fe.dofs.back() == FeDof{100, 6});
  const MassProperties before = mass_properties(t.fe, t.dof_position), after = mass_properties(tied.fe, tied.dof_position);
  CHECK(after.mass == Approx(before.mass).epsilon(1e-14));
  CHECK((after.centre - before.centre).norm() < 1e-14);
  CHECK((after.inertia - before.inertia).norm() < 1e-12 * before.inertia.norm());
  // Held at the master = the face's nodes held: the model's frequencies without their DOFs.
  std::vector<Eigen::Index> keep;
  for (std::size_t k = 0; k < t.fe.dofs.size(); ++k)
    if (std::find(face.begin(), face.end(), t.fe.dofs[k].node) == face.end()) keep.push_back(static_cast<Eigen::Index>(k));
  const Eigen::MatrixXd k = Eigen::MatrixXd(t.fe.stiffness), m = Eigen::MatrixXd(t.fe.mass);
  const Eigen::VectorXd exact = dense_frequencies(k(keep, keep), m(keep, keep));
  const ReducedPart part = craig_bampton(tied.fe, tied.dof_position, options({100}, 5));
  for (Eigen::Index j = 0; j < 5; ++j) CHECK(part.fixed_frequency[j] == Approx(exact[j]).epsilon(1e-9));
  // The tie carries a master motion to the face: a unit rotation about z turns node 1 by
  // e_z x (p1 - centre).
  const Eigen::VectorXd u = tied.tie.col(static_cast<Eigen::Index>(tied.fe.dofs.size()) - 1);
  const Eigen::Vector3d arm = t.node[0] - centre;
  CHECK(u.head<3>().isApprox(Eigen::Vector3d(-arm.y(), arm.x(), 0.0)));
  CHECK_THROWS_WITH(tie_rigidly(t.fe, t.dof_position, face, 3, centre), Catch::Contains("node 3 is in the model already"));
}
