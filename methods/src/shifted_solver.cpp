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

// matrix_ = I - gamma J. While J keeps its pattern only the numbers are written, through
// the slots found when the pattern first came; true when the sparse LU of the current kind
// has already analysed that pattern.
template <class Scalar>
bool ShiftedSolver<Scalar>::fill_sparse(const Eigen::SparseMatrix<double>& j, Scalar gamma) {
  const Eigen::Index n = j.rows(), nnz = j.nonZeros();
  const int* outer = j.outerIndexPtr();
  const int* inner = j.innerIndexPtr();
  const bool same = j.isCompressed() && static_cast<Eigen::Index>(slot_.size()) == nnz &&
                    std::equal(j_outer_.begin(), j_outer_.end(), outer, outer + n + 1) &&
                    std::equal(j_inner_.begin(), j_inner_.end(), inner, inner + nnz);
  if (!same) {
    Eigen::SparseMatrix<Scalar> identity(n, n);
    identity.setIdentity();
    matrix_ = (-gamma) * j.template cast<Scalar>() + identity;
    matrix_.makeCompressed();
    slot_.clear();
    diagonal_slot_.assign(static_cast<std::size_t>(n), 0);
    j_outer_.clear();
    j_inner_.clear();
    if (j.isCompressed()) {
      j_outer_.assign(outer, outer + n + 1);
      j_inner_.assign(inner, inner + nnz);
      slot_.reserve(static_cast<std::size_t>(nnz));
      for (Eigen::Index c = 0; c < n; ++c) {
        int at = matrix_.outerIndexPtr()[c];  // both columns are sorted by row
        for (int k = outer[c]; k < outer[c + 1]; ++k) {
          while (matrix_.innerIndexPtr()[at] != inner[k]) ++at;
          slot_.push_back(at);
        }
        at = matrix_.outerIndexPtr()[c];
        while (matrix_.innerIndexPtr()[at] != c) ++at;
        diagonal_slot_[static_cast<std::size_t>(c)] = at;
      }
    }
    sparse_.reset();
    klu_.reset();
    return false;
  }
  Scalar* v = matrix_.valuePtr();
  std::fill(v, v + matrix_.nonZeros(), Scalar(0));
  const double* jv = j.valuePtr();
  for (Eigen::Index k = 0; k < nnz; ++k) v[slot_[static_cast<std::size_t>(k)]] = -gamma * jv[k];
  for (int d : diagonal_slot_) v[d] += Scalar(1);
  return kind_ == LinearSolverKind::klu ? klu_ != nullptr : sparse_ != nullptr;
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
      const bool analysed = fill_sparse(j, gamma);
      if (!analysed) ++analyses_;
      if (kind_ == LinearSolverKind::klu) {
        if (!analysed) {
          sparse_.reset();
          klu_ = std::make_shared<KluLu<Scalar>>();
          klu_->analyze(matrix_);
        }
        klu_->factorize(matrix_);
        break;
      }
      if (!analysed) {
        klu_.reset();
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
long ShiftedSolver<Scalar>::refactorizations() const {
  return klu_ ? klu_->refactorizations() : 0;
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
