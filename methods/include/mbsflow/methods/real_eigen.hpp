#pragma once
// The eigenvalues and right eigenvectors of a real square matrix (Eigen's EigenSolver:
// Hessenberg reduction and the real Schur form). One function in one file so that the
// solver is compiled once for the whole program: each translation unit that instantiates
// EigenSolver<MatrixXd> spends about 12 s of compiler time on it.
#include <Eigen/Core>

namespace mbsflow {

struct RealEigen {
  Eigen::VectorXcd values;
  Eigen::MatrixXcd vectors;  // column i belongs to values(i); empty unless asked for
  bool converged = false;    // false when the QR iteration ran out of sweeps
};

RealEigen real_eigen(const Eigen::MatrixXd& a, bool with_vectors);

// The eigenvalues alone, as Eigen's MatrixBase::eigenvalues() gives them.
inline Eigen::VectorXcd eigenvalues_of(const Eigen::MatrixXd& a) { return real_eigen(a, false).values; }

}  // namespace mbsflow
