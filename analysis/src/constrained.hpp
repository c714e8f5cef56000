#pragma once
// The rigid joints' rows C in the linear algebra of a linearised model: the augmented
// matrix of the sparse solves (and its factors, as a solve on the allowed motions), and
// an orthonormal null-space basis for the dense ones.
//
// The augmented matrix [P C^T; C d I] of a linearised model: P on the bodies' coordinates,
// the rigid joints' rows C holding their motions, d on the multipliers' diagonal (a tiny
// negative d keeps a matrix with redundant rows regular; 0 puts the entry in the pattern).
#include <Eigen/QR>
#include <Eigen/SparseCore>
#include <utility>
#include <vector>

#include "mbsflow/methods/klu_lu.hpp"

namespace mbsflow {

// P made the augmented matrix in place: without rows, P itself (compressed). In place
// because Eigen 3.4's SparseMatrix has no move constructor: a matrix returned from a
// by-value parameter, or "moved", is copied, tens of millions of entries on a large model.
template <class Scalar>
void augment(Eigen::SparseMatrix<Scalar>& p, const Eigen::SparseMatrix<double>& c, Scalar d = Scalar(0)) {
  const Eigen::Index n = p.rows(), r = c.rows();
  p.makeCompressed();
  if (r == 0) return;
  std::vector<Eigen::Triplet<Scalar>> e;
  e.reserve(static_cast<std::size_t>(p.nonZeros() + 2 * c.nonZeros() + r));
  for (Eigen::Index col = 0; col < p.outerSize(); ++col)
    for (typename Eigen::SparseMatrix<Scalar>::InnerIterator it(p, col); it; ++it) e.emplace_back(it.row(), it.col(), it.value());
  for (Eigen::Index col = 0; col < c.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(c, col); it; ++it) {
      e.emplace_back(n + it.row(), it.col(), Scalar(it.value()));
      e.emplace_back(it.col(), n + it.row(), Scalar(it.value()));
    }
  for (Eigen::Index i = 0; i < r; ++i) e.emplace_back(n + i, n + i, d);
  p.resize(n + r, n + r);
  p.setFromTriplets(e.begin(), e.end());
  p.makeCompressed();
}

// P^-1 on the motions C x = 0 allows: x of [P C^T; C 0] [x; mu] = [b; 0], the augmented
// matrix factored once by KLU (the sparse eigensolvers' shifted inverses).
class ConstrainedSolve {
 public:
  void factor(Eigen::SparseMatrix<double> p, const Eigen::SparseMatrix<double>& c) {
    rows_ = c.rows();
    augment(p, c);
    lu_.analyze(p);
    lu_.factorize(p);
  }
  Eigen::VectorXd operator()(const Eigen::Ref<const Eigen::VectorXd>& b) const {
    Eigen::VectorXd x(b.size());
    solve_into(b, x);
    return x;
  }
  // The same into x, through a buffer kept from call to call (not for concurrent calls).
  void solve_into(const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::Ref<Eigen::VectorXd> x) const {
    rhs_.resize(b.size() + rows_);
    rhs_.head(b.size()) = b;
    rhs_.tail(rows_).setZero();
    lu_.solve(rhs_);
    x = rhs_.head(b.size());
  }

 private:
  KluLu<double> lu_;
  Eigen::Index rows_ = 0;
  mutable Eigen::VectorXd rhs_;
};

// Orthonormal basis of the null space of C (dense Householder QR of C^T), n x (n - rank);
// the identity without rows.
inline Eigen::MatrixXd null_space(const Eigen::SparseMatrix<double>& c, Eigen::Index n) {
  if (c.rows() == 0) return Eigen::MatrixXd::Identity(n, n);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Eigen::MatrixXd(c).transpose());
  qr.setThreshold(1e-10);
  const Eigen::MatrixXd q = qr.householderQ();
  return q.rightCols(n - qr.rank());
}

}  // namespace mbsflow
