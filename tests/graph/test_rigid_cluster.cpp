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

// The largest residual |S x - b| of the cluster's solve, relative to |b|, over a few b at once
// and one at a time.
double solve_residual(RigidCluster& rc, unsigned seed) {
  rc.factor();
  const Eigen::MatrixXd s = assembled(rc);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(s.rows(), 3, [&] { return u(gen); });
  Eigen::MatrixXd x = b;
  rc.solve(x);
  double worst = (s * x - b).norm() / b.norm();
  Eigen::VectorXd one = b.col(1);
  rc.solve(one);
  CHECK(one.isApprox(x.col(1), 1e-12));
  worst = std::max(worst, (s * one - b.col(1)).norm() / b.col(1).norm());
  return worst;
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
    // Two refinements leave (eps cond(S))^3 of the shifted solve's error, eps = 1e-6.
    CHECK(solve_residual(rc, 3u) < 1e-8);
    RigidCluster copy = rc;  // factored afresh, it solves bit for bit alike
    copy.factor();
    Eigen::VectorXd b = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(rc.rows.size())), x1 = b, x2 = b;
    rc.solve(x1);
    copy.solve(x2);
    CHECK(x1 == x2);
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
