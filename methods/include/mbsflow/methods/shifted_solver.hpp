#pragma once
// Factorisation and solution of (I - gamma J) x = b, J sparse, gamma real or complex: the
// linear systems of the simplified Newton iterations. The storage follows J's structure:
// dense LU for small systems, band LU when J is banded, sparse LU (Eigen's SparseLU with
// COLAMD ordering) otherwise.
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <complex>
#include <memory>
#include <string>

#include "mbsflow/methods/banded_lu.hpp"

namespace mbsflow {

enum class LinearSolverKind { automatic, dense, banded, sparse };
const char* to_string(LinearSolverKind k);
LinearSolverKind linear_solver_from_string(const std::string& name);  // throws InputError

struct Bandwidth {
  Eigen::Index lower = 0, upper = 0;
};
Bandwidth bandwidth_of(const Eigen::SparseMatrix<double>& j);

// automatic: dense up to 100 equations, banded when lower + upper <= 64, sparse otherwise.
LinearSolverKind choose_linear_solver(const Eigen::SparseMatrix<double>& j, LinearSolverKind wanted);

template <class Scalar>
class ShiftedSolver {
 public:
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  // Throws RunError when the matrix is singular.
  void factorize(const Eigen::SparseMatrix<double>& j, Scalar gamma, LinearSolverKind kind);
  void solve(Vector& b) const;  // in place
  LinearSolverKind kind() const { return kind_; }

 private:
  LinearSolverKind kind_ = LinearSolverKind::dense;
  Eigen::PartialPivLU<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>> dense_;
  BandedLU<Scalar> band_;
  std::shared_ptr<Eigen::SparseLU<Eigen::SparseMatrix<Scalar>, Eigen::COLAMDOrdering<int>>> sparse_;
};

extern template class ShiftedSolver<double>;
extern template class ShiftedSolver<std::complex<double>>;

}  // namespace mbsflow
