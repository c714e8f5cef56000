#pragma once
// SuiteSparse KLU (Davis & Palamadai Natarajan) behind one small class, real or complex:
// the sparse LU of the Newton matrices. analyze() (block triangular form, AMD ordering)
// is needed only when the pattern changes; factorize() redoes the numbers, reusing the
// last pivot sequence while it stays sound (refactorizations() counts those).
#include <Eigen/SparseCore>
#include <complex>
#include <memory>
#include <mutex>
#include <vector>

namespace mbsflow {

template <class Scalar>
class KluLu {
 public:
  KluLu();
  ~KluLu();
  KluLu(const KluLu&) = delete;
  KluLu& operator=(const KluLu&) = delete;
  // m: compressed, column-major. Both throw RunError on failure (a singular matrix).
  void analyze(const Eigen::SparseMatrix<Scalar>& m);
  void factorize(const Eigen::SparseMatrix<Scalar>& m);
  // In place. KLU solves in the factor's own workspace, so concurrent solves with one
  // factor (stages sharing a diagonal value) take turns.
  void solve(Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& b) const;
  long refactorizations() const { return refactorizations_; }

  // Checkpoints. The factors depend on the history: a refactorisation reuses the pivots
  // of the last full factorisation, whose values are kept (full_values) for restore(),
  // which rebuilds the factors of m (analysed) bit for bit: the full factorisation of
  // those values, then m's own values when the factors came from a refactorisation.
  const std::vector<Scalar>& full_values() const { return full_values_; }
  bool refactored() const { return refactored_; }
  void restore(const Eigen::SparseMatrix<Scalar>& m, const std::vector<Scalar>& full_values, bool refactored);

 private:
  struct Handles;
  std::unique_ptr<Handles> h_;
  std::vector<Scalar> full_values_;
  bool refactored_ = false;
  mutable std::mutex solving_;
  long refactorizations_ = 0;
};

extern template class KluLu<double>;
extern template class KluLu<std::complex<double>>;

}  // namespace mbsflow
