#pragma once
// Factorisation and solution of (I - gamma J) x = b, J sparse, gamma real or complex: the
// linear systems of the simplified Newton iterations. The storage follows J's structure:
// dense LU for small systems, band LU when J is banded, sparse LU otherwise: SuiteSparse
// KLU by default (faster on the multibody and heat matrices, docs/methods.md), or Eigen's
// SparseLU with COLAMD ordering. Both keep their symbolic analysis while the pattern of
// the matrix stays the same. With eliminate_first(), the sparse kinds eliminate small
// diagonal blocks of unknowns first and factorise the Schur complement of the rest
// (schur_reduction.hpp): a multibody model's positions and quaternions.
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <complex>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/methods/banded_lu.hpp"
#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/state_archive.hpp"

namespace mbsflow {

enum class LinearSolverKind { automatic, dense, banded, klu, sparselu };
const char* to_string(LinearSolverKind k);
LinearSolverKind linear_solver_from_string(const std::string& name);  // throws InputError

struct Bandwidth {
  Eigen::Index lower = 0, upper = 0;
};
Bandwidth bandwidth_of(const Eigen::SparseMatrix<double>& j);

// automatic: dense up to 100 equations, banded when lower + upper <= 64, klu otherwise.
LinearSolverKind choose_linear_solver(const Eigen::SparseMatrix<double>& j, LinearSolverKind wanted);

template <class Scalar>
class KluLu;  // klu_lu.hpp
struct SchurPattern;  // schur_reduction.hpp
class Elimination;
template <class Scalar>
class SchurReduction;

template <class Scalar>
class ShiftedSolver {
 public:
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  // Blocks of unknowns (OdeProblem::eliminable) that the dense and sparse kinds eliminate
  // before the LU where J's pattern allows (else they factorise the whole matrix). Set
  // before factorize; solvers of one integrator share one (make_elimination).
  void eliminate_first(std::shared_ptr<Elimination> e) { elimination_ = std::move(e); }
  // Whether the last factorisation was of the Schur complement.
  bool reduced() const { return schur_pattern_ != nullptr; }
  // Throws RunError when the matrix is singular.
  void factorize(const Eigen::SparseMatrix<double>& j, Scalar gamma, LinearSolverKind kind);
  void solve(Vector& b) const;  // in place
  LinearSolverKind kind() const { return kind_; }
  long symbolic_analyses() const { return analyses_; }  // sparse kinds: pattern analyses so far
  long refactorizations() const;  // klu: factorisations that reused the pivot sequence

  // Checkpoints: the factors as they are, rebuilt by restore() bit for bit (for KLU with
  // the pivot history it reuses). `pattern`: a Jacobian of the pattern it factorised
  // (the sparse kinds lay their matrix out from it).
  void save(StateWriter& out) const;
  void restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern);

 private:
  LinearSolverKind kind_ = LinearSolverKind::dense;
  Eigen::PartialPivLU<Eigen::MatrixXd> dense_;  // dense kind in real arithmetic
  BandedLU<Scalar> band_;  // banded kind; dense in complex arithmetic: a band as wide as the matrix
  Eigen::SparseMatrix<Scalar> matrix_;  // I - gamma J or its Schur complement, all kinds but banded
  std::vector<int> j_outer_, j_inner_;   // the pattern of the last J (note_pattern)
  std::optional<LinearSolverKind> chosen_;  // the automatic kind for that pattern, once asked for
  bool laid_out_ = false;                             // matrix_ is laid out for that pattern
  std::vector<int> slot_, diagonal_slot_;  // where J's entries and the identity go in matrix_
  std::shared_ptr<Elimination> elimination_;
  std::shared_ptr<const SchurPattern> schur_pattern_;  // matrix_ is the Schur complement
  std::shared_ptr<SchurReduction<Scalar>> schur_;
  std::shared_ptr<Eigen::SparseLU<Eigen::SparseMatrix<Scalar>, Eigen::COLAMDOrdering<int>>> sparse_;
  std::shared_ptr<KluLu<Scalar>> klu_;
  long analyses_ = 0;
  bool factorized_ = false;
  Eigen::SparseMatrix<double> dense_j_;  // dense and banded kinds: the J and gamma last factorised, for checkpoints
  Scalar dense_gamma_ = Scalar(0);
  bool fill_sparse(const Eigen::SparseMatrix<double>& j, Scalar gamma);
  void lay_out(const Eigen::SparseMatrix<double>& j);
  void note_pattern(const Eigen::SparseMatrix<double>& j);
};

// The shared elimination of a problem's blocks (OdeProblem::eliminable), or nullptr when it has none.
std::shared_ptr<Elimination> make_elimination(const std::vector<RowRange>& blocks);

extern template class ShiftedSolver<double>;
extern template class ShiftedSolver<std::complex<double>>;

}  // namespace mbsflow
