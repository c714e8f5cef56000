#pragma once
// LU factorisation with partial pivoting of a band matrix (kl sub-, ku superdiagonals),
// stored as LAPACK's dgbtrf does: row interchanges widen the upper band to kl + ku (no
// wider than the matrix: a band as wide as the matrix is a dense LU, which small Newton
// matrices use). Eigen has band storage but no band solver; this is the unblocked
// algorithm (gbtf2).
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

namespace mbsflow {

// a * b without the checks for infinite parts that std::complex's product makes (C99 Annex
// G): the factors here are finite, and the plain formula lets the loops vectorise.
inline double plain_product(double a, double b) { return a * b; }
inline std::complex<double> plain_product(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

template <class Scalar>
class BandedLU {
 public:
  BandedLU() = default;
  BandedLU(Eigen::Index n, Eigen::Index kl, Eigen::Index ku) { resize(n, kl, ku); }

  void resize(Eigen::Index n, Eigen::Index kl, Eigen::Index ku) {
    n_ = n;
    kl_ = kl;
    upper_ = std::min(kl + ku, std::max<Eigen::Index>(n - 1, 0));
    ld_ = kl + upper_ + 1;
    band_.assign(static_cast<std::size_t>(ld_ * n), Scalar(0));
    pivot_.assign(static_cast<std::size_t>(n), 0);
    inverse_diagonal_.assign(static_cast<std::size_t>(n), Scalar(0));
  }
  void set_zero() { std::fill(band_.begin(), band_.end(), Scalar(0)); }
  // Entry (i, j) of the matrix, |i - j| within the band (j - i <= ku before factorising).
  Scalar& at(Eigen::Index i, Eigen::Index j) { return band_[static_cast<std::size_t>(upper_ + i - j + j * ld_)]; }
  const Scalar& at(Eigen::Index i, Eigen::Index j) const {
    return band_[static_cast<std::size_t>(upper_ + i - j + j * ld_)];
  }
  Eigen::Index size() const { return n_; }

  // Throws RunError when a pivot is exactly zero (singular matrix).
  void factorize() {
    const Eigen::Index upper = upper_;
    for (Eigen::Index j = 0; j < n_; ++j) {
      const Eigen::Index below = std::min(kl_, n_ - 1 - j), right = std::min(upper, n_ - 1 - j);
      Eigen::Index p = 0;
      double best = std::norm(at(j, j));  // |.|^2: no square root (or hypot) per entry
      for (Eigen::Index r = 1; r <= below; ++r)
        if (std::norm(at(j + r, j)) > best) {
          best = std::norm(at(j + r, j));
          p = r;
        }
      pivot_[static_cast<std::size_t>(j)] = j + p;
      if (!(best > 0)) throw RunError("Newton matrix is singular");  // or not finite
      if (p != 0)
        for (Eigen::Index c = j; c <= j + right; ++c) std::swap(at(j, c), at(j + p, c));
      const Scalar inv = Scalar(1) / at(j, j);
      inverse_diagonal_[static_cast<std::size_t>(j)] = inv;
      for (Eigen::Index r = 1; r <= below; ++r) at(j + r, j) = plain_product(at(j + r, j), inv);
      for (Eigen::Index c = j + 1; c <= j + right; ++c) {
        const Scalar top = at(j, c);
        if (top == Scalar(0)) continue;
        for (Eigen::Index r = 1; r <= below; ++r) at(j + r, c) -= plain_product(at(j + r, j), top);
      }
    }
  }

  // Solves in place.
  template <class Vector>
  void solve(Vector& b) const {
    const Eigen::Index upper = upper_;
    for (Eigen::Index j = 0; j < n_; ++j) {
      const Eigen::Index p = pivot_[static_cast<std::size_t>(j)];
      if (p != j) std::swap(b(j), b(p));
      const Eigen::Index below = std::min(kl_, n_ - 1 - j);
      for (Eigen::Index r = 1; r <= below; ++r) b(j + r) -= plain_product(at(j + r, j), b(j));
    }
    for (Eigen::Index j = n_ - 1; j >= 0; --j) {
      b(j) = plain_product(b(j), inverse_diagonal_[static_cast<std::size_t>(j)]);  // a multiplication: complex division is slow
      const Eigen::Index top = std::max<Eigen::Index>(0, j - upper);
      for (Eigen::Index i = top; i < j; ++i) b(i) -= plain_product(at(i, j), b(j));
    }
  }

 private:
  Eigen::Index n_ = 0, kl_ = 0, upper_ = 0, ld_ = 1;  // upper_: the band above the diagonal after interchanges
  std::vector<Scalar> band_;
  std::vector<Eigen::Index> pivot_;
  std::vector<Scalar> inverse_diagonal_;
};

}  // namespace mbsflow
