#include "blas_product.hpp"

extern "C" {
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* b, const int* ldb, const double* beta, double* c, const int* ldc);
void dgemv_(const char* trans, const int* m, const int* n, const double* alpha, const double* a, const int* lda, const double* x,
            const int* incx, const double* beta, double* y, const int* incy);
}

namespace mbsflow {
namespace {

int size_of(Eigen::Index i) { return static_cast<int>(i); }

// C = op(a) b, op(a) = a^T where transposed.
Eigen::MatrixXd gemm(const Columns& a, const Columns& b, bool transposed) {
  Eigen::MatrixXd c(transposed ? a.cols() : a.rows(), b.cols());
  if (c.size() == 0) return c;
  if (b.rows() == 0) return c.setZero();
  const int m = size_of(c.rows()), n = size_of(c.cols()), k = size_of(b.rows());
  const int lda = size_of(a.outerStride()), ldb = size_of(b.outerStride());
  const double one = 1.0, zero = 0.0;
  dgemm_(transposed ? "T" : "N", "N", &m, &n, &k, &one, a.data(), &lda, b.data(), &ldb, &zero, c.data(), &m);
  return c;
}

}  // namespace

Eigen::MatrixXd transposed_product(const Columns& a, const Columns& b) { return gemm(a, b, true); }

Eigen::MatrixXd product(const Columns& a, const Columns& b) { return gemm(a, b, false); }

void transposed_times(const Columns& a, const double* x, double* out) {
  if (a.cols() == 0) return;
  const int m = size_of(a.rows()), n = size_of(a.cols()), lda = size_of(a.outerStride()), one_step = 1;
  const double one = 1.0, zero = 0.0;
  dgemv_("T", &m, &n, &one, a.data(), &lda, x, &one_step, &zero, out, &one_step);
}

void subtract_times(const Columns& a, const double* h, double* x) {
  if (a.cols() == 0 || a.rows() == 0) return;
  const int m = size_of(a.rows()), n = size_of(a.cols()), lda = size_of(a.outerStride()), one_step = 1;
  const double minus_one = -1.0, one = 1.0;
  dgemv_("N", &m, &n, &minus_one, a.data(), &lda, h, &one_step, &one, x, &one_step);
}

}  // namespace mbsflow
