#include "mbsflow/methods/real_eigen.hpp"

#include <Eigen/Eigenvalues>

namespace mbsflow {

RealEigen real_eigen(const Eigen::MatrixXd& a, bool with_vectors) {
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(a, with_vectors);
  RealEigen out;
  out.converged = eig.info() == Eigen::Success;
  out.values = eig.eigenvalues();
  if (with_vectors) out.vectors = eig.eigenvectors();
  return out;
}

}  // namespace mbsflow
