#include "mbsflow/methods/shifted_solver.hpp"

#include "klu_lu.hpp"
#include "mbsflow/error.hpp"

#include <algorithm>


namespace mbsflow {

const char* to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::automatic: return "auto";
    case LinearSolverKind::dense: return "dense";
    case LinearSolverKind::banded: return "banded";
    case LinearSolverKind::klu: return "klu";
    default: return "sparselu";
  }
}

LinearSolverKind linear_solver_from_string(const std::string& name) {
  for (LinearSolverKind k : {LinearSolverKind::automatic, LinearSolverKind::dense, LinearSolverKind::banded,
                             LinearSolverKind::klu, LinearSolverKind::sparselu})
    if (name == to_string(k)) return k;
  throw InputError("unknown linear solver '" + name + "' (auto, dense, banded, klu or sparselu)");
}

Bandwidth bandwidth_of(const Eigen::SparseMatrix<double>& j) {
  Bandwidth b;
  for (Eigen::Index c = 0; c < j.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(j, c); it; ++it) {
      b.lower = std::max(b.lower, it.row() - it.col());
      b.upper = std::max(b.upper, it.col() - it.row());
    }
  return b;
}

LinearSolverKind choose_linear_solver(const Eigen::SparseMatrix<double>& j, LinearSolverKind wanted) {
  if (wanted != LinearSolverKind::automatic) return wanted;
  if (j.rows() <= 100) return LinearSolverKind::dense;
  const Bandwidth b = bandwidth_of(j);
  return b.lower + b.upper <= 64 ? LinearSolverKind::banded : LinearSolverKind::klu;
}

template <class Scalar>
void ShiftedSolver<Scalar>::factorize(const Eigen::SparseMatrix<double>& j, Scalar gamma, LinearSolverKind kind) {
  kind_ = kind == LinearSolverKind::automatic ? choose_linear_solver(j, kind) : kind;
  const Eigen::Index n = j.rows();
  switch (kind_) {
    case LinearSolverKind::dense: {
      Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> m =
          Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>::Identity(n, n);
      for (Eigen::Index c = 0; c < j.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(j, c); it; ++it) m(it.row(), it.col()) -= gamma * it.value();
      dense_.compute(m);
      if (!(std::abs(dense_.determinant()) > 0)) throw RunError("Newton matrix is singular");
      break;
    }
    case LinearSolverKind::banded: {
      const Bandwidth b = bandwidth_of(j);
      band_.resize(n, b.lower, b.upper);
      for (Eigen::Index i = 0; i < n; ++i) band_.at(i, i) = Scalar(1);
      for (Eigen::Index c = 0; c < j.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(j, c); it; ++it) band_.at(it.row(), it.col()) -= gamma * it.value();
      band_.factorize();
      break;
    }
    default: {
      Eigen::SparseMatrix<Scalar> identity(n, n);
      identity.setIdentity();
      matrix_ = (-gamma) * j.template cast<Scalar>() + identity;
      matrix_.makeCompressed();
      const int* outer = matrix_.outerIndexPtr();
      const int* inner = matrix_.innerIndexPtr();
      const bool analysed = (kind_ == LinearSolverKind::klu ? klu_ != nullptr : sparse_ != nullptr) &&
                            std::equal(outer_.begin(), outer_.end(), outer, outer + n + 1) &&
                            std::equal(inner_.begin(), inner_.end(), inner, inner + matrix_.nonZeros());
      if (!analysed) {
        outer_.assign(outer, outer + n + 1);
        inner_.assign(inner, inner + matrix_.nonZeros());
        ++analyses_;
      }
      if (kind_ == LinearSolverKind::klu) {
        if (!analysed) {
          klu_ = std::make_shared<KluLu<Scalar>>();
          klu_->analyze(matrix_);
        }
        klu_->factorize(matrix_);
        break;
      }
      if (!analysed) {
        sparse_ = std::make_shared<Eigen::SparseLU<Eigen::SparseMatrix<Scalar>, Eigen::COLAMDOrdering<int>>>();
        sparse_->analyzePattern(matrix_);
      }
      sparse_->factorize(matrix_);
      if (sparse_->info() != Eigen::Success) throw RunError("Newton matrix is singular (sparse LU failed)");
      break;
    }
  }
}

template <class Scalar>
void ShiftedSolver<Scalar>::solve(Vector& b) const {
  switch (kind_) {
    case LinearSolverKind::dense: b = dense_.solve(b); break;
    case LinearSolverKind::banded: band_.solve(b); break;
    case LinearSolverKind::klu: klu_->solve(b); break;
    default: b = sparse_->solve(b); break;
  }
}

template class ShiftedSolver<double>;
template class ShiftedSolver<std::complex<double>>;

}  // namespace mbsflow
