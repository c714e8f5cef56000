#pragma once
// Cholesky factorisation S = L L^T of a small dense symmetric positive definite matrix, and
// solves with it, for the rigid clusters' constraint matrices (rigid_cluster.cpp: up to 48
// rows, factored at every right-hand side). At these sizes Eigen's LDLT and LLT spend more
// on a call per column than on the arithmetic. Here every inner loop is an update
// x[i] -= l[i] * c along contiguous memory, with no sum carried from one i to the next, so
// that the compiler vectorises it and no chain of dependent additions holds the core back.
#include <cmath>

namespace mbsflow::small_cholesky {

// a: n x n, column-major, S in its upper triangle (the lower one is overwritten). Leaves L
// in the lower triangle, L^T in the upper one, and 1 / L(k, k) in inverse_diagonal[k].
// False when a pivot is not positive (S not positive definite to rounding); a is then
// left partly factored.
inline bool factor(double* a, int n, double* inverse_diagonal) {
  for (int k = 0; k < n; ++k) {
    double* __restrict lk = a + static_cast<long>(k) * n;  // column k
    const double d = lk[k];
    if (!(d > 0.0)) return false;
    lk[k] = std::sqrt(d);
    const double inverse = 1.0 / lk[k];
    inverse_diagonal[k] = inverse;
    for (int j = k + 1; j < n; ++j) {
      const double l = a[k + static_cast<long>(j) * n] * inverse;  // row k of the reduced S
      lk[j] = l;
      a[k + static_cast<long>(j) * n] = l;
    }
    // The reduced S (upper triangle of rows and columns k + 1..n - 1) loses l l^T.
    for (int j = k + 1; j < n; ++j) {
      double* __restrict cj = a + static_cast<long>(j) * n;
      const double lj = lk[j];
      for (int i = k + 1; i <= j; ++i) cj[i] -= lk[i] * lj;
    }
  }
  return true;
}

// x <- S^-1 x with the factors of factor(), x of n numbers.
inline void solve(const double* a, int n, const double* inverse_diagonal, double* __restrict x) {
  for (int k = 0; k < n; ++k) {  // L z = x, column by column of L
    const double* __restrict lk = a + static_cast<long>(k) * n;
    const double z = x[k] * inverse_diagonal[k];
    x[k] = z;
    for (int i = k + 1; i < n; ++i) x[i] -= lk[i] * z;
  }
  for (int j = n - 1; j >= 0; --j) {  // L^T x = z, column by column of L^T
    const double* __restrict uj = a + static_cast<long>(j) * n;
    const double v = x[j] * inverse_diagonal[j];
    x[j] = v;
    for (int i = 0; i < j; ++i) x[i] -= uj[i] * v;
  }
}

}  // namespace mbsflow::small_cholesky
