#include "mbsflow/error.hpp"
#include "mbsflow/methods/shifted_solver.hpp"


namespace mbsflow {

const char* to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::automatic: return "auto";
    case LinearSolverKind::dense: return "dense";
    case LinearSolverKind::banded: return "banded";
    default: return "sparse";
  }
}

LinearSolverKind linear_solver_from_string(const std::string& name) {
  for (LinearSolverKind k : {LinearSolverKind::automatic, LinearSolverKind::dense, LinearSolverKind::banded,
                             LinearSolverKind::sparse})
    if (name == to_string(k)) return k;
  throw InputError("unknown linear solver '" + name + "' (auto, dense, banded or sparse)");
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
  return b.lower + b.upper <= 64 ? LinearSolverKind::banded : LinearSolverKind::sparse;
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
      Eigen::SparseMatrix<Scalar> m = (-gamma) * j.template cast<Scalar>();
      Eigen::SparseMatrix<Scalar> identity(n, n);
      identity.setIdentity();
      m += identity;
      m.makeCompressed();
      sparse_ = std::make_shared<Eigen::SparseLU<Eigen::SparseMatrix<Scalar>, Eigen::COLAMDOrdering<int>>>();
      sparse_->compute(m);
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
    default: b = sparse_->solve(b); break;
  }
}

template class ShiftedSolver<double>;
template class ShiftedSolver<std::complex<double>>;

}  // namespace mbsflow
