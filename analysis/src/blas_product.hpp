#pragma once
// Dense products on tall blocks of columns (rows of the model's or the FE part's size)
// through BLAS (the system's libblas.so.3: OpenBLAS where installed), whose blocked and
// threaded kernels run them several times faster than a portable build of Eigen's: the
// reduction's products, whose cost grows with the interface squared, and the Arnoldi
// basis's orthogonalisation (gemv on a million rows: 3x Eigen's on this machine).
#include <Eigen/Core>

namespace mbsflow {

using Columns = Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;  // blocks of columns, no copy
Eigen::MatrixXd transposed_product(const Columns& a, const Columns& b);

// a b.
Eigen::MatrixXd product(const Columns& a, const Columns& b);

// out = a^T x (a.cols() numbers; x has a.rows()).
void transposed_times(const Columns& a, const double* x, double* out);

// x -= a h (h has a.cols() numbers).
void subtract_times(const Columns& a, const double* h, double* x);

}  // namespace mbsflow
