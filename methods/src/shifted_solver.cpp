#include "mbsflow/methods/shifted_solver.hpp"

#include "mbsflow/methods/klu_lu.hpp"
#include "scalar_archive.hpp"
#include "schur_reduction.hpp"
#include "mbsflow/error.hpp"

#include <algorithm>
#include <type_traits>


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

namespace {

// Compressed, with every column sorted by row (as the merge below needs).
bool compressed_and_sorted(const Eigen::SparseMatrix<double>& j) {
  if (!j.isCompressed()) return false;
  const int* outer = j.outerIndexPtr();
  const int* inner = j.innerIndexPtr();
  for (Eigen::Index c = 0; c < j.outerSize(); ++c)
    if (!std::is_sorted(inner + outer[c], inner + outer[c + 1])) return false;
  return true;
}

// J itself when compressed with sorted columns, else such a copy in `storage` (a
// transposed copy of a transpose has its columns sorted).
const Eigen::SparseMatrix<double>& tidy(const Eigen::SparseMatrix<double>& given, Eigen::SparseMatrix<double>& storage) {
  if (compressed_and_sorted(given)) return given;
  const Eigen::SparseMatrix<double, Eigen::RowMajor> t = given;
  storage = t;
  storage.makeCompressed();
  return storage;
}

// m: n x n, compressed, with the pattern outer / inner and zero values.
template <class Scalar>
void set_pattern(Eigen::SparseMatrix<Scalar>& m, Eigen::Index n, const std::vector<int>& outer, const std::vector<int>& inner) {
  m = Eigen::SparseMatrix<Scalar>(n, n);
  m.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), m.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), m.innerIndexPtr());
}

}  // namespace

// What depends on J's pattern only is worked out once per pattern: the automatic choice of
// kind (when asked for) and (fill_sparse) the layout of the sparse matrix. A pattern is
// kept for comparison when J is compressed with sorted columns (as the Jacobian evaluators
// make it).
template <class Scalar>
void ShiftedSolver<Scalar>::note_pattern(const Eigen::SparseMatrix<double>& j) {
  if (same_pattern(j_outer_, j_inner_, j)) return;
  j_outer_.clear();
  j_inner_.clear();
  if (compressed_and_sorted(j)) {
    j_outer_.assign(j.outerIndexPtr(), j.outerIndexPtr() + j.outerSize() + 1);
    j_inner_.assign(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros());
  }
  chosen_.reset();
  laid_out_ = false;
}

// matrix_ = I - gamma J, or its Schur complement when blocks can be eliminated. While J
// keeps its pattern only the numbers are written, through the slots found when the
// pattern first came; true when the sparse LU of the current kind has already analysed
// that pattern. After note_pattern(given).
template <class Scalar>
bool ShiftedSolver<Scalar>::fill_sparse(const Eigen::SparseMatrix<double>& given, Scalar gamma) {
  Eigen::SparseMatrix<double> sorted;
  const Eigen::SparseMatrix<double>& j = j_outer_.empty() ? tidy(given, sorted) : given;  // a kept pattern is tidy
  const Eigen::Index nnz = j.nonZeros();
  if (!laid_out_) {
    schur_pattern_ = elimination_ ? elimination_->pattern_for(j) : nullptr;
    if (schur_pattern_) {
      set_pattern(matrix_, schur_pattern_->kept_count, schur_pattern_->s_outer, schur_pattern_->s_inner);
      schur_ = std::make_shared<SchurReduction<Scalar>>();
    } else {
      lay_out(j);
    }
    laid_out_ = !j_outer_.empty();  // an untidy J is laid out anew every time
    sparse_.reset();
    klu_.reset();
  }
  Scalar* v = matrix_.valuePtr();
  if (schur_pattern_) {
    schur_->reduce(*schur_pattern_, j, gamma, v);
  } else {
    std::fill(v, v + matrix_.nonZeros(), Scalar(0));
    const double* jv = j.valuePtr();
    for (Eigen::Index k = 0; k < nnz; ++k) v[slot_[static_cast<std::size_t>(k)]] = -gamma * jv[k];
    for (int d : diagonal_slot_) v[d] += Scalar(1);
  }
  return kind_ == LinearSolverKind::klu ? klu_ != nullptr : sparse_ != nullptr;
}

// The pattern of I - gamma J: J's columns merged with the diagonal, written directly (an
// Eigen expression over complex entries took a tenth of a short run's time), and where
// each entry of J and of the identity lands.
template <class Scalar>
void ShiftedSolver<Scalar>::lay_out(const Eigen::SparseMatrix<double>& j) {
  const Eigen::Index n = j.rows(), nnz = j.nonZeros();
  const int* outer = j.outerIndexPtr();
  const int* inner = j.innerIndexPtr();
  slot_.assign(static_cast<std::size_t>(nnz), 0);
  diagonal_slot_.assign(static_cast<std::size_t>(n), 0);
  std::vector<int> m_outer(static_cast<std::size_t>(n + 1)), m_inner;
  m_inner.reserve(static_cast<std::size_t>(nnz + n));
  for (Eigen::Index c = 0; c < n; ++c) {
    m_outer[static_cast<std::size_t>(c)] = static_cast<int>(m_inner.size());
    bool diagonal = false;
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      if (!diagonal && inner[k] >= c) {
        diagonal = true;
        diagonal_slot_[static_cast<std::size_t>(c)] = static_cast<int>(m_inner.size());
        if (inner[k] > c) m_inner.push_back(static_cast<int>(c));
      }
      slot_[static_cast<std::size_t>(k)] = static_cast<int>(m_inner.size());
      m_inner.push_back(inner[k]);
    }
    if (!diagonal) {
      diagonal_slot_[static_cast<std::size_t>(c)] = static_cast<int>(m_inner.size());
      m_inner.push_back(static_cast<int>(c));
    }
  }
  m_outer[static_cast<std::size_t>(n)] = static_cast<int>(m_inner.size());
  set_pattern(matrix_, n, m_outer, m_inner);
}

template <class Scalar>
void ShiftedSolver<Scalar>::factorize(const Eigen::SparseMatrix<double>& j, Scalar gamma, LinearSolverKind kind) {
  note_pattern(j);
  if (kind == LinearSolverKind::automatic && !chosen_) chosen_ = choose_linear_solver(j, kind);
  kind_ = kind == LinearSolverKind::automatic ? *chosen_ : kind;
  const Eigen::Index n = j.rows();
  factorized_ = false;
  if (kind_ == LinearSolverKind::dense || kind_ == LinearSolverKind::banded) {
    dense_j_ = j;
    dense_gamma_ = gamma;
  }
  switch (kind_) {
    case LinearSolverKind::dense: {
      // Through matrix_, so that eliminable blocks go first here too: a multibody model's
      // positions and quaternions leave its velocities (A05: 24 unknowns of 52, a tenth of
      // the LU's work).
      fill_sparse(j, gamma);
      if constexpr (std::is_same_v<Scalar, double>) {
        dense_.compute(Eigen::MatrixXd(matrix_));
        if (!(std::abs(dense_.determinant()) > 0)) throw RunError("Newton matrix is singular");
      } else {
        // A complex matrix as a band as wide as itself: Eigen's PartialPivLU takes each
        // candidate pivot's |z| by hypot and was 2-2.5x slower at 10-50 unknowns (BandedLU
        // compares |z|^2); in real arithmetic Eigen's blocked LU is as fast, and faster at 100.
        const Eigen::Index m = matrix_.rows();
        band_.resize(m, m - 1, m - 1);
        for (Eigen::Index c = 0; c < m; ++c)
          for (typename Eigen::SparseMatrix<Scalar>::InnerIterator it(matrix_, c); it; ++it) band_.at(it.row(), c) = it.value();
        band_.factorize();
      }
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
  factorized_ = true;
}

template <class Scalar>
void ShiftedSolver<Scalar>::save(StateWriter& out) const {
  out.flag(factorized_);
  if (!factorized_) return;
  out.integer(static_cast<int>(kind_));
  if (kind_ == LinearSolverKind::dense || kind_ == LinearSolverKind::banded) {
    out.sparse(dense_j_);
    out.vector(as_reals(&dense_gamma_, 1));
    return;
  }
  out.flag(schur_pattern_ != nullptr);
  if (schur_pattern_) schur_->save(out);
  out.vector(as_reals(matrix_.valuePtr(), matrix_.nonZeros()));
  if (kind_ == LinearSolverKind::klu) {
    out.vector(as_reals(klu_->full_values().data(), static_cast<Eigen::Index>(klu_->full_values().size())));
    out.flag(klu_->refactored());
  }
}

template <class Scalar>
void ShiftedSolver<Scalar>::restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern) {
  factorized_ = false;
  if (!in.flag()) return;
  const auto kind = static_cast<LinearSolverKind>(in.integer(1, static_cast<int>(LinearSolverKind::sparselu)));
  if (kind == LinearSolverKind::dense || kind == LinearSolverKind::banded) {
    const Eigen::SparseMatrix<double> j = in.sparse();
    const std::vector<Scalar> gamma = from_reals<Scalar>(in.vector(), in);
    if (gamma.size() != 1) in.fail("a Newton matrix's shift is not one number");
    factorize(j, gamma[0], kind);
    return;
  }
  kind_ = kind;
  note_pattern(pattern);
  fill_sparse(pattern, Scalar(0));  // the layout of I - gamma J, and where J's entries go
  if (in.flag() != (schur_pattern_ != nullptr)) in.fail("a Newton matrix reduced otherwise than its Jacobian's pattern allows");
  if (schur_pattern_) schur_->restore(in);
  const std::vector<Scalar> values = from_reals<Scalar>(in.vector(), in);
  if (static_cast<Eigen::Index>(values.size()) != matrix_.nonZeros()) in.fail("a Newton matrix does not fit the Jacobian's pattern");
  std::copy(values.begin(), values.end(), matrix_.valuePtr());
  ++analyses_;
  if (kind_ == LinearSolverKind::klu) {
    const std::vector<Scalar> full = from_reals<Scalar>(in.vector(), in);
    const bool refactored = in.flag();
    sparse_.reset();
    klu_ = std::make_shared<KluLu<Scalar>>();
    klu_->analyze(matrix_);
    klu_->restore(matrix_, full, refactored);
  } else {
    klu_.reset();
    sparse_ = std::make_shared<Eigen::SparseLU<Eigen::SparseMatrix<Scalar>, Eigen::COLAMDOrdering<int>>>();
    sparse_->analyzePattern(matrix_);
    sparse_->factorize(matrix_);
    if (sparse_->info() != Eigen::Success) in.fail("a Newton matrix that was factorised is singular now");
  }
  factorized_ = true;
}

template <class Scalar>
long ShiftedSolver<Scalar>::refactorizations() const {
  return klu_ ? klu_->refactorizations() : 0;
}

template <class Scalar>
void ShiftedSolver<Scalar>::solve(Vector& b) const {
  if (kind_ == LinearSolverKind::banded) return band_.solve(b);
  // The other kinds factorised matrix_: I - gamma J or its Schur complement.
  auto solve_matrix = [this](Vector& x) {
    if (kind_ == LinearSolverKind::dense) {
      if constexpr (std::is_same_v<Scalar, double>)
        x = dense_.solve(x);
      else
        band_.solve(x);
    } else if (kind_ == LinearSolverKind::klu)
      klu_->solve(x);
    else
      x = sparse_->solve(x);
  };
  if (schur_pattern_)
    schur_->solve(b, solve_matrix);
  else
    solve_matrix(b);
}

std::shared_ptr<Elimination> make_elimination(const std::vector<RowRange>& blocks) {
  return blocks.empty() ? nullptr : std::make_shared<Elimination>(blocks);
}

template class ShiftedSolver<double>;
template class ShiftedSolver<std::complex<double>>;

}  // namespace mbsflow
