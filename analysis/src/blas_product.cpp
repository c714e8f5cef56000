#include "blas_product.hpp"

extern "C" void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k, const double* alpha,
                       const double* a, const int* lda, const double* b, const int* ldb, const double* beta, double* c,
                       const int* ldc);

namespace mbsflow {

Eigen::MatrixXd transposed_product(const Columns& a, const Columns& b) {
  Eigen::MatrixXd c(a.cols(), b.cols());
  if (c.size() == 0) return c;
  if (a.rows() == 0) return c.setZero();
  const int m = static_cast<int>(a.cols()), n = static_cast<int>(b.cols()), k = static_cast<int>(a.rows());
  const int lda = static_cast<int>(a.outerStride()), ldb = static_cast<int>(b.outerStride());
  const double one = 1.0, zero = 0.0;
  dgemm_("T", "N", &m, &n, &k, &one, a.data(), &lda, b.data(), &ldb, &zero, c.data(), &m);
  return c;
}

}  // namespace mbsflow
