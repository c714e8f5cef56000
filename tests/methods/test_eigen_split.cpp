// The eigenvalue split of the simplified Newton systems (I - tau G (x) J) dU = -R: the
// systems of the real eigenvalues and complex pairs together give the solution of the
// whole Kronecker system, for tableaux with real eigenvalues only, pairs only, and both.
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <vector>

#include "eigen_split.hpp"
#include "mbsflow/methods/rk_tableau.hpp"

using namespace mbsflow;

namespace {

Eigen::SparseMatrix<double> some_jacobian(Eigen::Index n) {
  // Stiff, nonsymmetric, with a negative diagonal and couplings of mixed sign.
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    d(i, i) = -1000.0 * double(i + 1);
    if (i + 1 < n) {
      d(i, i + 1) = 37.0 - 5.0 * double(i);
      d(i + 1, i) = -11.0 + 3.0 * double(i);
    }
  }
  d(0, n - 1) = 5.0;
  return d.sparseView();
}

}  // namespace

TEST_CASE("eigen split: the real and complex systems solve the whole Kronecker system", "[methods][linear]") {
  const Eigen::Index n = 6;
  const Eigen::SparseMatrix<double> j = some_jacobian(n);
  const double tau = 0.01;
  for (const char* name : {"radau2", "radau3", "radau5", "gauss3", "lobatto3c"}) {
    const RkTableau t = rk_tableau(name);
    const Eigen::MatrixXd a = t.implicit_block();
    const auto k = static_cast<int>(a.rows());
    EigenSplit split(a, n, name);
    int pairs = 0;
    for (int e = 0; e < split.systems(); ++e) pairs += split.is_complex(e);
    CHECK(split.systems() == k - pairs);  // one system per real eigenvalue or pair
    for (int e = 0; e < split.systems(); ++e) split.factorize(e, j, tau, LinearSolverKind::dense);
    // The residuals, stage-major, and the reference: the dense Kronecker solve.
    std::vector<Eigen::VectorXd> r(static_cast<std::size_t>(k));
    Eigen::VectorXd r_all(k * n);
    for (int i = 0; i < k; ++i) {
      r[static_cast<std::size_t>(i)] = Eigen::VectorXd::LinSpaced(n, 1.0 + i, -2.0 * i);
      r_all.segment(i * n, n) = r[static_cast<std::size_t>(i)];
    }
    Eigen::MatrixXd kron(k * n, k * n);
    const Eigen::MatrixXd jd(j);
    for (int i = 0; i < k; ++i)
      for (int l = 0; l < k; ++l) kron.block(i * n, l * n, n, n) = -tau * a(i, l) * jd;
    kron += Eigen::MatrixXd::Identity(k * n, k * n);
    const Eigen::VectorXd expect = kron.partialPivLu().solve(-r_all);
    // In two slices of rows, as the flow graph's nodes do.
    split.load_residuals(r, 0, 4);
    split.load_residuals(r, 4, n - 4);
    for (int e = 0; e < split.systems(); ++e) split.solve(e);
    double worst = 0;
    Eigen::VectorXd du;
    for (int i = 0; i < k; ++i) {
      split.correction(i, 0, n, du);
      worst = std::max(worst, (du - expect.segment(i * n, n)).cwiseAbs().maxCoeff());
    }
    INFO(name << ": " << pairs << " pairs, largest difference " << worst);
    CHECK(worst <= 1e-12 * expect.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("eigen split: a real eigenvalue of Radau IIA is found for the error estimate's filter", "[methods][linear]") {
  const RkTableau t = rk_tableau("radau3");
  const double gamma = largest_real_eigenvalue(t);
  CHECK(gamma == Approx(0.2748888295956773));  // 1 / 3.6378..., Radau5's gamma0
  EigenSplit split(t.implicit_block(), 3, "radau3");
  CHECK(split.real_system(gamma) >= 0);
  CHECK(split.real_system(0.5) == -1);
  CHECK(largest_real_eigenvalue(rk_tableau("radau2")) == 0);  // a complex pair only
}
