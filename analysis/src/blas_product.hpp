#pragma once
// A^T B for tall A and B (rows of the FE model's size): the products of the reduction
// whose cost grows with the interface squared, through BLAS (the system's libblas.so.3:
// OpenBLAS where installed), whose blocked kernels run them several times faster than a
// portable build of Eigen's.
#include <Eigen/Core>

namespace mbsflow {

using Columns = Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;  // blocks of columns, no copy
Eigen::MatrixXd transposed_product(const Columns& a, const Columns& b);

}  // namespace mbsflow
