// Newton matrices with small blocks eliminated first (schur_reduction.hpp): the Schur
// complement gives the solution of the whole system, real and complex, with KLU, SparseLU
// and the dense LU; blocks that read each other are left in; a singular block is refused;
// the factors survive a checkpoint bit for bit.
#include <catch2/catch.hpp>

#include <complex>
#include <random>

#include "mbsflow/methods/shifted_solver.hpp"
#include "schur_reduction.hpp"

using namespace mbsflow;

namespace {

// The shape of a multibody Jacobian over a chain of `bodies`, laid out as the state is
// (all positions, quaternions, velocities, angular velocities): r' = v and
// q' = Omega(w) q / 2 + Q(q) w read only their own body; the accelerations read the
// states of the body and its neighbours. Random numbers of magnitude `stiffness` in
// the accelerations. cross_block: also q0' reads q1 (the blocks then do not qualify).
Eigen::SparseMatrix<double> chain_jacobian(int bodies, double stiffness, bool cross_block = false) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 13 * bodies;
  auto r = [&](int b) { return 3 * b; };
  auto q = [&](int b) { return 3 * bodies + 4 * b; };
  auto v = [&](int b) { return 7 * bodies + 3 * b; };
  auto w = [&](int b) { return 10 * bodies + 3 * b; };
  std::vector<Eigen::Triplet<double>> t;
  for (int b = 0; b < bodies; ++b) {
    for (int i = 0; i < 3; ++i) t.emplace_back(r(b) + i, v(b) + i, 1.0);
    for (int i = 0; i < 4; ++i) {
      for (int k = 0; k < 4; ++k)
        if (k != i) t.emplace_back(q(b) + i, q(b) + k, 3.0 * u(rng));
      for (int k = 0; k < 3; ++k) t.emplace_back(q(b) + i, w(b) + k, 0.5 * u(rng));
    }
    for (int a = std::max(0, b - 1); a <= std::min(bodies - 1, b + 1); ++a)
      for (int row : {v(b), w(b)})
        for (int i = 0; i < 3; ++i) {
          for (int k = 0; k < 3; ++k) {
            t.emplace_back(row + i, r(a) + k, stiffness * u(rng));
            t.emplace_back(row + i, v(a) + k, 0.01 * stiffness * u(rng));
            t.emplace_back(row + i, w(a) + k, 0.01 * stiffness * u(rng));
          }
          for (int k = 0; k < 4; ++k) t.emplace_back(row + i, q(a) + k, stiffness * u(rng));
        }
  }
  for (int b = 0; b < bodies; ++b)  // every acceleration damps itself: a well-posed Newton matrix
    for (int i = 0; i < 3; ++i) {
      t.emplace_back(v(b) + i, v(b) + i, -stiffness);
      t.emplace_back(w(b) + i, w(b) + i, -stiffness);
    }
  if (cross_block) t.emplace_back(q(0), q(1), 1.0);
  Eigen::SparseMatrix<double> j(n, n);
  j.setFromTriplets(t.begin(), t.end());
  j.makeCompressed();
  return j;
}

std::vector<RowRange> blocks_of(int bodies) {
  std::vector<RowRange> out;
  for (int b = 0; b < bodies; ++b) out.push_back({3 * b, 3 * b + 3});
  for (int b = 0; b < bodies; ++b) out.push_back({3 * bodies + 4 * b, 3 * bodies + 4 * b + 4});
  return out;
}

template <class Scalar>
using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

template <class Scalar>
Vector<Scalar> some_rhs(Eigen::Index n) {
  Vector<Scalar> b(n);
  for (Eigen::Index i = 0; i < n; ++i) b[i] = Scalar(std::sin(0.7 * i) + 0.1 * i / n);
  return b;
}

// max |x - y| / max |y|
template <class Scalar>
double relative_gap(const Vector<Scalar>& x, const Vector<Scalar>& y) {
  return (x - y).cwiseAbs().maxCoeff() / y.cwiseAbs().maxCoeff();
}

template <class Scalar>
void solves_like_the_full_matrix(Scalar gamma, LinearSolverKind kind) {
  const int bodies = 40;
  const Eigen::SparseMatrix<double> j = chain_jacobian(bodies, 1e4);
  ShiftedSolver<Scalar> full, reduced;
  reduced.eliminate_first(make_elimination(blocks_of(bodies)));
  full.factorize(j, gamma, kind);
  reduced.factorize(j, gamma, kind);
  CHECK_FALSE(full.reduced());
  CHECK(reduced.reduced());
  const Vector<Scalar> b = some_rhs<Scalar>(j.rows());
  Vector<Scalar> x_full = b, x_reduced = b;
  full.solve(x_full);
  reduced.solve(x_reduced);
  CHECK(relative_gap<Scalar>(x_reduced, x_full) < 1e-11);
  const Vector<Scalar> residual = x_reduced - gamma * (j.template cast<Scalar>() * x_reduced) - b;
  CHECK(residual.cwiseAbs().maxCoeff() < 1e-10 * b.cwiseAbs().maxCoeff() * (1 + std::abs(gamma) * 1e4));
  // New numbers, the same pattern: no new analysis.
  const Eigen::SparseMatrix<double> j2 = 0.5 * j;
  reduced.factorize(j2, gamma, kind);
  full.factorize(j2, gamma, kind);
  CHECK(reduced.symbolic_analyses() == (kind == LinearSolverKind::dense ? 0 : 1));  // dense: no analysis
  x_full = b;
  x_reduced = b;
  full.solve(x_full);
  reduced.solve(x_reduced);
  CHECK(relative_gap<Scalar>(x_reduced, x_full) < 1e-11);
}

}  // namespace

TEST_CASE("eliminated blocks: the Schur complement solves the Newton systems like the whole matrix",
          "[methods][linear]") {
  // Dense too: A05's 52 unknowns become its 24 velocities before the LU.
  for (LinearSolverKind kind : {LinearSolverKind::klu, LinearSolverKind::sparselu, LinearSolverKind::dense}) {
    INFO(to_string(kind));
    solves_like_the_full_matrix<double>(2e-3, kind);
    solves_like_the_full_matrix<std::complex<double>>({1.5e-3, 8e-4}, kind);
  }
}

TEST_CASE("eliminated blocks: S keeps the velocity unknowns with the body-pair pattern", "[methods][linear]") {
  const int bodies = 10;
  const auto p = make_schur_pattern(chain_jacobian(bodies, 1.0), blocks_of(bodies));
  REQUIRE(p);
  CHECK(p->kept_count == 6 * bodies);
  CHECK(p->eliminated == 7 * bodies);
  // Every body reads itself and its neighbours: 6 x 6 blocks on three block diagonals.
  CHECK(static_cast<long>(p->s_inner.size()) == 36L * (3 * bodies - 2));
}

TEST_CASE("blocks that read each other or do not fit are not eliminated", "[methods][linear]") {
  const int bodies = 12;
  const Eigen::SparseMatrix<double> crossed = chain_jacobian(bodies, 1e3, true);
  CHECK_FALSE(make_schur_pattern(crossed, blocks_of(bodies)));
  ShiftedSolver<double> solver;
  solver.eliminate_first(make_elimination(blocks_of(bodies)));
  solver.factorize(crossed, 1e-3, LinearSolverKind::klu);
  CHECK_FALSE(solver.reduced());  // the whole matrix, still solved
  Vector<double> x = some_rhs<double>(crossed.rows());
  const Vector<double> b = x;
  solver.solve(x);
  CHECK((x - 1e-3 * (crossed * x) - b).cwiseAbs().maxCoeff() < 1e-10);

  const Eigen::SparseMatrix<double> j = chain_jacobian(bodies, 1e3);
  std::vector<RowRange> overlapping = blocks_of(bodies);
  overlapping.push_back({2, 5});
  CHECK_FALSE(make_schur_pattern(j, overlapping));
  CHECK_FALSE(make_schur_pattern(j, {{0, 17}}));            // larger than 16
  CHECK_FALSE(make_schur_pattern(j, {{0, j.rows() + 1}}));  // outside
  CHECK(make_elimination({}) == nullptr);
}

TEST_CASE("a singular eliminated block is refused", "[methods][linear]") {
  // J = I on a 2-block: I - 1 * J = 0 there.
  std::vector<Eigen::Triplet<double>> t{{0, 0, 1.0}, {1, 1, 1.0}, {0, 2, 1.0}, {2, 0, 1.0}, {2, 2, -1.0}};
  Eigen::SparseMatrix<double> j(3, 3);
  j.setFromTriplets(t.begin(), t.end());
  j.makeCompressed();
  ShiftedSolver<double> solver;
  solver.eliminate_first(make_elimination({{0, 2}}));
  CHECK_THROWS_WITH(solver.factorize(j, 1.0, LinearSolverKind::klu), Catch::Contains("eliminated block"));
}

TEST_CASE("reduced Newton factors survive a checkpoint bit for bit", "[methods][linear]") {
  const int bodies = 20;
  const Eigen::SparseMatrix<double> j = chain_jacobian(bodies, 1e4);
  const std::complex<double> gamma(1e-3, 6e-4);
  for (LinearSolverKind kind : {LinearSolverKind::klu, LinearSolverKind::dense}) {
    INFO(to_string(kind));
    ShiftedSolver<std::complex<double>> before, after;
    before.eliminate_first(make_elimination(blocks_of(bodies)));
    after.eliminate_first(make_elimination(blocks_of(bodies)));
    before.factorize(j, gamma, kind);
    before.factorize(1.01 * j, gamma, kind);  // a refactorisation
    StateWriter out;
    before.save(out);
    StateReader in(out.data(), "test");
    after.restore(in, j);
    CHECK(after.reduced());
    Vector<std::complex<double>> x = some_rhs<std::complex<double>>(j.rows()), y = x;
    before.solve(x);
    after.solve(y);
    CHECK(x == y);
  }
}
