#pragma once
// The rigid joints of one cluster of bodies (bodies joined by rigid joints, ground and
// the rest of the model outside), solved together: the constraint matrix
//   S = J W J^T + eps I,  W = blockdiag(1/m I, R J^-1 R^T) per body (0 for a driven body),
// assembled from the rows and factored (dense Cholesky for small clusters, sparse LDLT with
// AMD ordering otherwise, so that chains and trees cost in proportion to their bodies).
// eps = 1e-6 times each diagonal entry makes S positive definite also when rows are
// redundant (a planar loop modelled in 3D) or the mechanism is at a singular position
// (the redundant part of the multipliers lies in the null space of J^T and exerts no
// force); two steps of iterative refinement against the unshifted S reduce the bias
// where S is regular, and keep the multipliers bounded where it is (nearly) singular.
// An S whose factorisation shows it regular is solved as it is, unshifted and unrefined
// (factor()).
// S is assembled body by body (J_b W_b J_b^T over the rows on body b) straight into its
// AMD-permuted upper triangle, so the factorisation needs no copy.
// Everything about a cluster is numbered inside it (bodies ascending, joints ascending),
// so a submodel holding the cluster does the same arithmetic as the whole model.
#include <Eigen/Core>
#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <memory>
#include <vector>

#include "constraint_rows.hpp"

namespace mbsflow {

using Vector6d = Eigen::Matrix<double, 6, 1>;

namespace cluster_solve {
inline constexpr double relative_shift = 1e-6;  // eps / diagonal entry (A02 error vs eps: docs/joints.md)
inline constexpr int refinements = 2;           // iterative refinement steps against the unshifted S
// Smallest ratio of a pivot of the unshifted S (dense Cholesky or sparse LDLT) to its
// diagonal entry at which S is solved as it is: below it S is near singular (a redundant
// row gives 1e-8 or less, or no Cholesky at all) and gets the shift and refinements.
inline constexpr double regular_pivot_ratio = 1e-8;
}  // namespace cluster_solve

struct ClusterJoint {
  int joint = 0;      // index in the system's joints
  int a = -1, b = -1;  // body slots in the cluster; -1: ground
  int first_row = 0, rows = 0;
};

class RigidCluster {
 public:
  RigidCluster(std::vector<int> bodies, std::vector<ClusterJoint> joints);
  // A copy gets its own sparse factorisation (analysed again), never a shared one.
  RigidCluster(const RigidCluster& o);
  RigidCluster& operator=(const RigidCluster& o);
  RigidCluster(RigidCluster&&) = default;
  RigidCluster& operator=(RigidCluster&&) = default;
  ~RigidCluster();

  const std::vector<int>& bodies() const { return bodies_; }
  const std::vector<ClusterJoint>& joints() const { return joints_; }
  int row_count() const { return rows_count_; }

  // Filled by the caller before factor(): every row, and per body slot its inverse mass
  // and world inverse inertia (zeros for a driven body).
  std::vector<ConstraintRow> rows;
  std::vector<double> inv_mass;
  std::vector<Eigen::Matrix3d> inv_inertia;

  void factor();
  // x <- S^-1 x, for one right-hand side or for each column of x at once (the Jacobian's
  // columns, cluster_jacobian.cpp: blocked triangular solves in place of one per column).
  void solve(Eigen::VectorXd& x) const;
  void solve(Eigen::MatrixXd& x) const;
  // Per body slot, the wrench J^T lambda (force, torque; world).
  void wrenches(const Eigen::Ref<const Eigen::VectorXd>& lambda, std::vector<Vector6d>& out) const;
  // Per body slot, W J^T lambda: the velocity (or position) change the multipliers make.
  void motion(const Eigen::Ref<const Eigen::VectorXd>& lambda, std::vector<Vector6d>& out) const;

 private:
  int slot(int r, int side) const { return side == 0 ? row_a_[static_cast<std::size_t>(r)] : row_b_[static_cast<std::size_t>(r)]; }
  Vector6d part(int r, int side) const { return rows[static_cast<std::size_t>(r)].j.segment<6>(6 * side); }
  Vector6d weighted(int slot, const Vector6d& j) const;
  void analyse();
  bool factor_dense_cholesky();

  std::vector<int> bodies_;
  std::vector<ClusterJoint> joints_;
  int rows_count_ = 0;
  std::vector<int> row_a_, row_b_;  // body slot of each row's two sides
  // Per body slot: the row sides on it (row * 2 + side), and for each pair p >= q of them
  // the value index of their entry of S.
  std::vector<std::vector<int>> on_body_;
  std::vector<std::vector<int>> scatter_;
  std::vector<int> diagonal_;  // value index of each diagonal entry
  std::vector<int> position_;  // sparse: row -> its index in the permuted matrix
  bool dense_ = true;
  Eigen::MatrixXd dense_matrix_;
  // Cholesky factors of S + eps (positive definite; small_cholesky.hpp), or a pivoted
  // LDLT where rounding leaves a pivot of the Cholesky not positive.
  Eigen::MatrixXd dense_cholesky_;
  Eigen::VectorXd cholesky_inverse_diagonal_;
  Eigen::LDLT<Eigen::MatrixXd, Eigen::Upper> dense_ldlt_;
  enum class DenseFactors { none, cholesky, ldlt };
  DenseFactors dense_factors_ = DenseFactors::none;  // which is current (none: not yet computed, not to be copied)
  bool shifted_ = true;  // the factors are of S + eps (refined in solves), not of S itself
  Eigen::SparseMatrix<double> sparse_matrix_;  // upper triangle, permuted
  using SparseLdlt = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>;
  std::unique_ptr<SparseLdlt> sparse_ldlt_;
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> block_j_, block_jw_;  // scratch
  std::vector<double> shift_;  // eps added to each row's diagonal entry
  mutable Eigen::VectorXd permuted_, rhs_, residual_;
  mutable Eigen::MatrixXd permuted_columns_, rhs_columns_, residual_columns_;
  template <class X>
  void solve_shifted(X& y) const;
  template <class X>
  void refined_solve(X& x, X& rhs, X& permuted, X& residual) const;
};

}  // namespace mbsflow
