// The rigid clusters' constraint solve (graph/src/rigid_cluster.hpp) against the matrix
// S = J W J^T assembled and solved by Eigen, on clusters with random rows: the small dense
// Cholesky (small_cholesky.hpp), its fallback where S is not positive definite, and the
// sparse path past the dense limit.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <random>

#include "rigid_cluster.hpp"
#include "small_cholesky.hpp"

using namespace mbsflow;

namespace {

// A chain of `bodies` bodies from ground, each link a joint of `rows` rows with random
// Jacobian entries; body masses and inertias random and positive unless `negative_mass`.
RigidCluster random_cluster(int bodies, int rows, unsigned seed, bool negative_mass = false) {
  std::vector<int> ids(static_cast<std::size_t>(bodies));
  std::vector<ClusterJoint> joints;
  for (int b = 0; b < bodies; ++b) {
    ids[static_cast<std::size_t>(b)] = 10 + b;
    joints.push_back({b, b - 1, b, b * rows, rows});  // body b-1 (ground for b = 0) to body b
  }
  RigidCluster rc(ids, joints);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (ConstraintRow& r : rc.rows)
    for (int e = 0; e < 12; ++e) r.j[e] = u(gen);
  for (int b = 0; b < bodies; ++b) {
    rc.inv_mass[static_cast<std::size_t>(b)] = 1.5 + u(gen);
    const Eigen::Matrix3d a = Eigen::Matrix3d::NullaryExpr([&] { return u(gen); });
    rc.inv_inertia[static_cast<std::size_t>(b)] = a * a.transpose() + Eigen::Matrix3d::Identity();
  }
  if (negative_mass) rc.inv_mass[0] = -50.0;  // S indefinite: no Cholesky
  return rc;
}

// S = J W J^T, from the rows and weights as the cluster holds them.
Eigen::MatrixXd assembled(const RigidCluster& rc) {
  const auto m = static_cast<Eigen::Index>(rc.rows.size());
  const auto nb = static_cast<Eigen::Index>(rc.bodies().size());
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(m, 6 * nb), w = Eigen::MatrixXd::Zero(6 * nb, 6 * nb);
  for (const ClusterJoint& cj : rc.joints())
    for (int r = cj.first_row; r < cj.first_row + cj.rows; ++r) {
      const RowJacobian& row = rc.rows[static_cast<std::size_t>(r)].j;
      if (cj.a >= 0) j.block<1, 6>(r, 6 * cj.a) = row.head<6>().transpose();
      if (cj.b >= 0) j.block<1, 6>(r, 6 * cj.b) = row.tail<6>().transpose();
    }
  for (Eigen::Index b = 0; b < nb; ++b) {
    w.block<3, 3>(6 * b, 6 * b) = rc.inv_mass[static_cast<std::size_t>(b)] * Eigen::Matrix3d::Identity();
    w.block<3, 3>(6 * b + 3, 6 * b + 3) = rc.inv_inertia[static_cast<std::size_t>(b)];
  }
  return j * w * j.transpose();
}

// The largest backward error |S x - b| / (|S| |x|) of the cluster's solve over a few b at
// once and one at a time: a few units of rounding for an exact solve of S, whatever its
// condition.
double solve_residual(RigidCluster& rc, unsigned seed) {
  rc.factor();
  const Eigen::MatrixXd s = assembled(rc);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(s.rows(), 3, [&] { return u(gen); });
  Eigen::MatrixXd x = b;
  rc.solve(x);
  double worst = 0;
  for (Eigen::Index c = 0; c < b.cols(); ++c)
    worst = std::max(worst, (s * x.col(c) - b.col(c)).norm() / (s.norm() * x.col(c).norm()));
  Eigen::VectorXd one = b.col(1);
  rc.solve(one);
  CHECK(one.isApprox(x.col(1), 1e-12));
  return std::max(worst, (s * one - b.col(1)).norm() / (s.norm() * one.norm()));
}

}  // namespace

TEST_CASE("small_cholesky factors and solves as Eigen's LLT does and refuses an indefinite matrix", "[graph][cluster]") {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n : {1, 2, 5, 20, 48}) {
    INFO("n = " << n);
    const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return u(gen); });
    const Eigen::MatrixXd s = a * a.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    Eigen::MatrixXd f = s;
    f.triangularView<Eigen::StrictlyLower>().setConstant(12345.0);  // only the upper triangle is read
    Eigen::VectorXd inverse_diagonal(n);
    REQUIRE(small_cholesky::factor(f.data(), n, inverse_diagonal.data()));
    const Eigen::MatrixXd l = s.llt().matrixL();
    CHECK(Eigen::MatrixXd(f.triangularView<Eigen::Lower>()).isApprox(l, 1e-12));
    CHECK(Eigen::MatrixXd(f.triangularView<Eigen::Upper>()).isApprox(l.transpose(), 1e-12));
    CHECK(inverse_diagonal.isApprox(l.diagonal().cwiseInverse(), 1e-12));
    const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(n, [&] { return u(gen); });
    Eigen::VectorXd x = b;
    small_cholesky::solve(f.data(), n, inverse_diagonal.data(), x.data());
    CHECK(x.isApprox(s.llt().solve(b), 1e-9));
  }
  Eigen::Vector3d inverse_diagonal;
  Eigen::Matrix3d indefinite;
  indefinite << 1, 2, 0, 2, 1, 0, 0, 0, 1;  // eigenvalues 3, 1, -1
  CHECK_FALSE(small_cholesky::factor(indefinite.data(), 3, inverse_diagonal.data()));
  Eigen::Matrix3d singular = Eigen::Matrix3d::Zero();
  CHECK_FALSE(small_cholesky::factor(singular.data(), 3, inverse_diagonal.data()));
}

TEST_CASE("a rigid cluster's solve matches S = J W J^T on the dense and the sparse path", "[graph][cluster]") {
  // 3 bodies of 5 rows: 15 rows, dense; 12 bodies of 5 rows: 60 rows, past the dense limit.
  for (int bodies : {3, 12}) {
    RigidCluster rc = random_cluster(bodies, 5, 11u + static_cast<unsigned>(bodies));
    INFO(bodies << " bodies");
    // Both paths solve a regular S as it is: the backward error is rounding's.
    CHECK(solve_residual(rc, 3u) < 1e-14);
    RigidCluster copy = rc;  // factored afresh, it solves bit for bit alike
    copy.factor();
    Eigen::VectorXd b = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(rc.rows.size())), x1 = b, x2 = b;
    rc.solve(x1);
    copy.solve(x2);
    CHECK(x1 == x2);
  }
}

TEST_CASE("a small regular cluster is solved exactly and one with redundant rows is regularised", "[graph][cluster]") {
  SECTION("regular and ill-conditioned: S^-1 b to rounding") {
    // 3 bodies of 5 rows (15 rows, 18 coordinates); body 1 turns about one axis with an
    // inertia 1e6 times its others' (as A05's rods about their own axes): the smallest
    // Cholesky pivot is about 1e-5 of its diagonal entry, and the shift's refinements would
    // leave (1e-6 / 1e-5)^3 of the multipliers' error.
    RigidCluster rc = random_cluster(3, 5, 21u);
    rc.inv_inertia[1] = Eigen::Vector3d(1.0, 1.0, 1e6).asDiagonal();
    rc.factor();
    const Eigen::MatrixXd s = assembled(rc);
    const Eigen::VectorXd pivots = s.llt().matrixL().toDenseMatrix().diagonal();
    const double smallest = (pivots.array().square() / s.diagonal().array()).minCoeff();
    INFO("smallest pivot ratio " << smallest);
    REQUIRE(smallest < 1e-4);
    REQUIRE(smallest > 1e-8);
    CHECK(solve_residual(rc, 6u) < 1e-14);
  }
  SECTION("redundant rows: bounded multipliers that meet S x = b") {
    // Two bodies, and the second body's joint twice: 15 rows for 12 coordinates.
    std::vector<ClusterJoint> joints{{0, -1, 0, 0, 5}, {1, 0, 1, 5, 5}, {2, 0, 1, 10, 5}};
    RigidCluster rc({10, 11}, joints);
    RigidCluster donor = random_cluster(2, 5, 8u);
    for (int r = 0; r < 10; ++r) rc.rows[static_cast<std::size_t>(r)] = donor.rows[static_cast<std::size_t>(r)];
    for (int r = 0; r < 5; ++r) rc.rows[static_cast<std::size_t>(10 + r)] = donor.rows[static_cast<std::size_t>(5 + r)];
    rc.inv_mass = donor.inv_mass;
    rc.inv_inertia = donor.inv_inertia;
    rc.factor();
    const Eigen::MatrixXd s = assembled(rc);
    const Eigen::VectorXd b = s * Eigen::VectorXd::LinSpaced(15, -1.0, 2.0);  // in S's range
    Eigen::VectorXd x = b;
    rc.solve(x);
    CHECK((s * x - b).norm() < 1e-6 * b.norm());
    CHECK(x.norm() < 1e3 * b.norm() / s.norm() + 10.0);  // not blown up along the null space
  }
}

TEST_CASE("a rigid cluster whose S is not positive definite is still solved (pivoted LDLT)", "[graph][cluster]") {
  // A negative inverse mass makes S indefinite: the Cholesky finds a pivot below zero, and
  // the pivoted LDLT takes over; the refined solve still meets S x = b.
  RigidCluster rc = random_cluster(3, 5, 5u, true);
  const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(assembled(rc)).eigenvalues();
  REQUIRE(eig.minCoeff() < -1.0);
  REQUIRE(eig.cwiseAbs().minCoeff() > 1e-3);  // regular: the solve is exact to rounding
  CHECK(solve_residual(rc, 4u) < 1e-10);
}
