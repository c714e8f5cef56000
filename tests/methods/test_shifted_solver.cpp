// The sparse LUs of the Newton matrices (I - gamma J) x = b: KLU and SparseLU solve them
// like the dense LU, real and complex, and analyse the pattern only when it changes.
#include <catch2/catch.hpp>

#include <complex>

#include "mbsflow/methods/shifted_solver.hpp"

using namespace mbsflow;

namespace {

// A tridiagonal J with a coupling to a far column: not banded enough to hide the pattern.
Eigen::SparseMatrix<double> jacobian(int n, double scale) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, -2.0 * scale - 0.01 * i);
    if (i > 0) t.emplace_back(i, i - 1, scale);
    if (i + 1 < n) t.emplace_back(i, i + 1, scale);
  }
  t.emplace_back(0, n - 1, 0.5 * scale);
  Eigen::SparseMatrix<double> j(n, n);
  j.setFromTriplets(t.begin(), t.end());
  j.makeCompressed();
  return j;
}

template <class Scalar>
double residual_after_solve(ShiftedSolver<Scalar>& solver, const Eigen::SparseMatrix<double>& j, Scalar gamma,
                            LinearSolverKind kind) {
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  solver.factorize(j, gamma, kind);
  const Vector b = Vector::LinSpaced(j.rows(), Scalar(1.0), Scalar(2.0));
  Vector x = b;
  solver.solve(x);
  const Vector ax = x - gamma * (j.template cast<Scalar>() * x);
  return (ax - b).cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("sparse Newton matrices: KLU and SparseLU solve them and keep their analysis while the pattern stays",
          "[methods][linear]") {
  for (LinearSolverKind kind : {LinearSolverKind::klu, LinearSolverKind::sparselu}) {
    INFO(to_string(kind));
    ShiftedSolver<double> real;
    ShiftedSolver<std::complex<double>> complex;
    for (int k = 0; k < 3; ++k) {  // new values and shifts, the same pattern
      CHECK(residual_after_solve(real, jacobian(300, 1.0 + k), 0.1 * (k + 1), kind) < 1e-10);
      CHECK(residual_after_solve(complex, jacobian(300, 1.0 + k), std::complex<double>(0.1, 0.05 * k), kind) < 1e-10);
    }
    CHECK(real.kind() == kind);
    // KLU refactors the later matrices with the first one's pivot sequence.
    CHECK(real.refactorizations() == (kind == LinearSolverKind::klu ? 2 : 0));
    CHECK(real.symbolic_analyses() == 1);
    CHECK(complex.symbolic_analyses() == 1);
    CHECK(residual_after_solve(real, jacobian(200, 1.0), 0.3, kind) < 1e-10);  // another pattern
    CHECK(real.symbolic_analyses() == 2);
  }
  CHECK(linear_solver_from_string("klu") == LinearSolverKind::klu);
}

TEST_CASE("KLU picks new pivots when the old sequence meets a zero pivot", "[methods][linear]") {
  // J full 2 x 2; with gamma = 1, I - J has a zero where the first factorisation pivoted.
  auto j = [](double j00) {
    Eigen::SparseMatrix<double> m(2, 2);
    const std::vector<Eigen::Triplet<double>> t{{0, 0, j00}, {0, 1, 1.0}, {1, 0, 1.0}, {1, 1, -1.0}};
    m.setFromTriplets(t.begin(), t.end());
    m.makeCompressed();
    return m;
  };
  ShiftedSolver<double> solver;
  CHECK(residual_after_solve(solver, j(-1.0), 1.0, LinearSolverKind::klu) < 1e-12);
  CHECK(residual_after_solve(solver, j(0.2), 1.0, LinearSolverKind::klu) < 1e-12);
  CHECK(solver.refactorizations() == 1);
  CHECK(residual_after_solve(solver, j(1.0), 1.0, LinearSolverKind::klu) < 1e-12);  // 1 - 1 = 0 on the diagonal
  CHECK(solver.refactorizations() == 1);
  CHECK(solver.symbolic_analyses() == 1);
  CHECK_THROWS_WITH(linear_solver_from_string("sparse"), Catch::Contains("auto, dense, banded, klu or sparselu"));
}
