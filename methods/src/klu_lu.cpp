#include "mbsflow/methods/klu_lu.hpp"

#include <klu.h>

#include "mbsflow/error.hpp"

namespace mbsflow {

template <class Scalar>
struct KluLu<Scalar>::Handles {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  double full_rcond = 0;  // of the last full factorisation
  static constexpr bool complex = !std::is_same_v<Scalar, double>;
  void free_numeric() {
    if (!numeric) return;
    if constexpr (complex)
      klu_z_free_numeric(&numeric, &common);
    else
      klu_free_numeric(&numeric, &common);
  }
  ~Handles() {
    free_numeric();
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
};

template <class Scalar>
KluLu<Scalar>::KluLu() : h_(std::make_unique<Handles>()) {
  klu_defaults(&h_->common);
}

template <class Scalar>
KluLu<Scalar>::~KluLu() = default;

template <class Scalar>
void KluLu<Scalar>::analyze(const Eigen::SparseMatrix<Scalar>& m) {
  h_->free_numeric();
  if (h_->symbolic) klu_free_symbolic(&h_->symbolic, &h_->common);
  h_->symbolic = klu_analyze(static_cast<int>(m.rows()), const_cast<int*>(m.outerIndexPtr()),
                             const_cast<int*>(m.innerIndexPtr()), &h_->common);
  if (!h_->symbolic) throw RunError("sparse LU (KLU): the analysis of the Newton matrix failed");
}

template <class Scalar>
void KluLu<Scalar>::factorize(const Eigen::SparseMatrix<Scalar>& m) {
  int* ap = const_cast<int*>(m.outerIndexPtr());
  int* ai = const_cast<int*>(m.innerIndexPtr());
  auto* values = reinterpret_cast<double*>(const_cast<Scalar*>(m.valuePtr()));
  klu_common& c = h_->common;
  // With factors at hand, refactor: the same pivot sequence with new numbers, without the
  // pivot search (several times faster). Kept only while the pivots stay sound: KLU's cheap
  // reciprocal condition estimate (min |u_ii| / max |u_ii|) within a factor 1000 of the
  // last full factorisation's; else a full factorisation picks new pivots.
  if (h_->numeric) {
    int ok;
    if constexpr (Handles::complex)
      ok = klu_z_refactor(ap, ai, values, h_->symbolic, h_->numeric, &c) && klu_z_rcond(h_->symbolic, h_->numeric, &c);
    else
      ok = klu_refactor(ap, ai, values, h_->symbolic, h_->numeric, &c) && klu_rcond(h_->symbolic, h_->numeric, &c);
    if (ok && c.status == KLU_OK && c.rcond > 1e-3 * h_->full_rcond) {
      ++refactorizations_;
      refactored_ = true;
      return;
    }
    h_->free_numeric();
  }
  if constexpr (Handles::complex)
    h_->numeric = klu_z_factor(ap, ai, values, h_->symbolic, &c);
  else
    h_->numeric = klu_factor(ap, ai, values, h_->symbolic, &c);
  if (!h_->numeric || c.status == KLU_SINGULAR) {
    h_->free_numeric();
    throw RunError("Newton matrix is singular (sparse LU, KLU)");
  }
  if constexpr (Handles::complex)
    klu_z_rcond(h_->symbolic, h_->numeric, &c);
  else
    klu_rcond(h_->symbolic, h_->numeric, &c);
  h_->full_rcond = c.rcond;
  full_values_.assign(m.valuePtr(), m.valuePtr() + m.nonZeros());
  refactored_ = false;
}

template <class Scalar>
void KluLu<Scalar>::restore(const Eigen::SparseMatrix<Scalar>& m, const std::vector<Scalar>& full_values, bool refactored) {
  if (static_cast<Eigen::Index>(full_values.size()) != m.nonZeros())
    throw InputError("checkpoint: the sparse LU's values do not fit the Newton matrix");
  Eigen::SparseMatrix<Scalar> full = m;
  std::copy(full_values.begin(), full_values.end(), full.valuePtr());
  h_->free_numeric();
  factorize(full);  // no factors: a full factorisation, the same pivots as then
  if (refactored) factorize(m);
}

template <class Scalar>
void KluLu<Scalar>::solve(Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& b) const {
  const int n = static_cast<int>(b.size());
  auto* values = reinterpret_cast<double*>(b.data());
  std::lock_guard lock(solving_);
  if constexpr (Handles::complex)
    klu_z_solve(h_->symbolic, h_->numeric, n, 1, values, &h_->common);
  else
    klu_solve(h_->symbolic, h_->numeric, n, 1, values, &h_->common);
}

template class KluLu<double>;
template class KluLu<std::complex<double>>;

}  // namespace mbsflow
