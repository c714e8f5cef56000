#include "rigid_cluster.hpp"

#include <algorithm>
#include <map>
#include <numeric>

#include <Eigen/OrderingMethods>

#include "small_cholesky.hpp"

namespace mbsflow {
namespace {
constexpr int dense_limit = 48;        // rows up to which the dense factorisation is used
using namespace cluster_solve;
}  // namespace

RigidCluster::RigidCluster(std::vector<int> bodies, std::vector<ClusterJoint> joints)
    : bodies_(std::move(bodies)), joints_(std::move(joints)) {
  for (const ClusterJoint& j : joints_) {
    for (int r = 0; r < j.rows; ++r) {
      row_a_.push_back(j.a);
      row_b_.push_back(j.b);
    }
    rows_count_ += j.rows;
  }
  const int m = rows_count_;
  rows.resize(static_cast<std::size_t>(m));
  inv_mass.assign(bodies_.size(), 0.0);
  inv_inertia.assign(bodies_.size(), Eigen::Matrix3d::Zero());
  dense_ = m <= dense_limit;
  on_body_.resize(bodies_.size());
  for (int r = 0; r < m; ++r)
    for (int side = 0; side < 2; ++side)
      if (const int b = slot(r, side); b >= 0) on_body_[static_cast<std::size_t>(b)].push_back(2 * r + side);
  // Where row r sits in the factored matrix: itself (dense), or its AMD position.
  position_.resize(static_cast<std::size_t>(m));
  std::iota(position_.begin(), position_.end(), 0);
  if (!dense_) {
    std::vector<Eigen::Triplet<double>> lower;
    for (int r = 0; r < m; ++r) lower.emplace_back(r, r, 1.0);
    for (const auto& list : on_body_)
      for (std::size_t p = 0; p < list.size(); ++p)
        for (std::size_t q = 0; q < p; ++q)
          lower.emplace_back(std::max(list[p], list[q]) / 2, std::min(list[p], list[q]) / 2, 1.0);
    Eigen::SparseMatrix<double> pattern(m, m);
    pattern.setFromTriplets(lower.begin(), lower.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
    Eigen::AMDOrdering<int>()(pattern, inverse);  // AMD gives the inverse permutation
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order = inverse.inverse();
    for (int r = 0; r < m; ++r) position_[static_cast<std::size_t>(r)] = order.indices()[r];
  }
  // Entries of the upper triangle (row <= column, at the factored positions), in
  // column-major order: the order of a compressed sparse matrix's values.
  std::map<std::pair<int, int>, int> entry;  // (column, row) -> value index
  auto key = [&](int r, int s) {
    const int a = position_[static_cast<std::size_t>(r)], b = position_[static_cast<std::size_t>(s)];
    return std::make_pair(std::max(a, b), std::min(a, b));
  };
  for (int r = 0; r < m; ++r) entry.emplace(key(r, r), 0);
  for (const auto& list : on_body_)
    for (std::size_t p = 0; p < list.size(); ++p)
      for (std::size_t q = 0; q <= p; ++q) entry.emplace(key(list[p] / 2, list[q] / 2), 0);
  if (dense_) {
    for (auto& [k, value] : entry) value = k.second + m * k.first;
    dense_matrix_.setZero(m, m);
  } else {
    std::vector<Eigen::Triplet<double>> upper;
    for (auto& [k, value] : entry) {
      value = static_cast<int>(upper.size());
      upper.emplace_back(k.second, k.first, 0.0);
    }
    sparse_matrix_.resize(m, m);
    sparse_matrix_.setFromTriplets(upper.begin(), upper.end());
    sparse_matrix_.makeCompressed();
    analyse();
  }
  for (int r = 0; r < m; ++r) diagonal_.push_back(entry.at(key(r, r)));
  shift_.assign(static_cast<std::size_t>(m), 0.0);
  permuted_.resize(m);
  rhs_.resize(m);
  residual_.resize(m);
  for (const auto& list : on_body_) {
    std::vector<int>& to = scatter_.emplace_back();
    for (std::size_t p = 0; p < list.size(); ++p)
      for (std::size_t q = 0; q <= p; ++q) to.push_back(entry.at(key(list[p] / 2, list[q] / 2)));
  }
}

RigidCluster::RigidCluster(const RigidCluster& o)
    : rows(o.rows), inv_mass(o.inv_mass), inv_inertia(o.inv_inertia), bodies_(o.bodies_), joints_(o.joints_),
      rows_count_(o.rows_count_), row_a_(o.row_a_), row_b_(o.row_b_), on_body_(o.on_body_), scatter_(o.scatter_),
      diagonal_(o.diagonal_), position_(o.position_), dense_(o.dense_), dense_matrix_(o.dense_matrix_),
      dense_factors_(o.dense_factors_), shifted_(o.shifted_), sparse_matrix_(o.sparse_matrix_), shift_(o.shift_), permuted_(o.permuted_),
      rhs_(o.rhs_), residual_(o.residual_) {
  if (dense_factors_ == DenseFactors::cholesky) {
    dense_cholesky_ = o.dense_cholesky_;
    cholesky_inverse_diagonal_ = o.cholesky_inverse_diagonal_;
  }
  if (dense_factors_ == DenseFactors::ldlt) dense_ldlt_ = o.dense_ldlt_;
  if (!dense_) analyse();
}

RigidCluster& RigidCluster::operator=(const RigidCluster& o) {
  if (this != &o) *this = RigidCluster(o);
  return *this;
}

RigidCluster::~RigidCluster() = default;

void RigidCluster::analyse() {
  sparse_ldlt_ = std::make_unique<SparseLdlt>();
  sparse_ldlt_->analyzePattern(sparse_matrix_);
}

Vector6d RigidCluster::weighted(int b, const Vector6d& j) const {
  const auto i = static_cast<std::size_t>(b);
  Vector6d out;
  out.head<3>() = inv_mass[i] * j.head<3>();
  out.tail<3>() = inv_inertia[i] * j.tail<3>();
  return out;
}

void RigidCluster::factor() {
  double* value = dense_ ? dense_matrix_.data() : sparse_matrix_.valuePtr();
  if (dense_)
    dense_matrix_.setZero();
  else
    std::fill(value, value + sparse_matrix_.nonZeros(), 0.0);
  // Body by body: J_b W_b J_b^T over the row sides on body b.
  for (std::size_t b = 0; b < on_body_.size(); ++b) {
    const std::vector<int>& list = on_body_[b];
    const auto k = static_cast<Eigen::Index>(list.size());
    block_j_.resize(k, 6);
    for (Eigen::Index p = 0; p < k; ++p)
      block_j_.row(p) = part(list[static_cast<std::size_t>(p)] / 2, list[static_cast<std::size_t>(p)] % 2).transpose();
    block_jw_.resize(k, 6);
    block_jw_.leftCols<3>() = inv_mass[b] * block_j_.leftCols<3>();
    block_jw_.rightCols<3>() = block_j_.rightCols<3>() * inv_inertia[b];  // symmetric
    // The block is symmetric: each pair q <= p once, scattered into S's upper triangle.
    const int* to = scatter_[b].data();
    for (Eigen::Index p = 0; p < k; ++p)
      for (Eigen::Index q = 0; q <= p; ++q) value[*to++] += block_jw_.row(p).dot(block_j_.row(q));
  }
  // An S that is regular is solved as it is: its Cholesky succeeds with no pivot below
  // regular_pivot_ratio of its diagonal entry. Then no refinement is needed, and the
  // multipliers are S^-1 b to rounding, where the shift's two refinements leave
  // (eps / ratio)^3 of it (A05's smallest ratio is about 1e-5). More rows than the free
  // bodies' 6 coordinates each are redundant for sure (a planar loop in 3D): then the
  // attempt is not made, as it would only fail.
  // The sparse LDLT is tried the same way, its D holding the pivots (permuted numbering).
  const auto free_bodies = std::count_if(inv_mass.begin(), inv_mass.end(), [](double w) { return w != 0.0; });
  if (rows_count_ <= 6 * free_bodies) {
    bool regular = true;
    if (dense_) {
      regular = factor_dense_cholesky();
      for (std::size_t r = 0; regular && r < diagonal_.size(); ++r) {
        const double pivot = dense_cholesky_(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r));
        regular = pivot * pivot >= regular_pivot_ratio * value[diagonal_[r]];
      }
    } else {
      sparse_ldlt_->factorize(sparse_matrix_);
      regular = sparse_ldlt_->info() == Eigen::Success;
      const Eigen::VectorXd& pivots = sparse_ldlt_->vectorD();  // a copy: Eigen returns D by value
      for (std::size_t r = 0; regular && r < diagonal_.size(); ++r) {
        const double pivot = pivots[position_[r]];
        regular = pivot > 0.0 && pivot >= regular_pivot_ratio * value[diagonal_[r]];
      }
    }
    if (regular) {
      if (dense_) dense_factors_ = DenseFactors::cholesky;
      shifted_ = false;
      return;
    }
  }
  // Else each diagonal entry grows by eps of itself: the same relative regularisation for
  // rows in metres and in radians, and for light and heavy bodies alike.
  shifted_ = true;
  for (std::size_t r = 0; r < diagonal_.size(); ++r) {
    shift_[r] = relative_shift * value[diagonal_[r]] + 1e-300;
    value[diagonal_[r]] += shift_[r];
  }
  if (dense_) {
    dense_factors_ = DenseFactors::cholesky;
    if (!factor_dense_cholesky()) {
      dense_ldlt_.compute(dense_matrix_);
      dense_factors_ = DenseFactors::ldlt;
    }
  } else {
    sparse_ldlt_->factorize(sparse_matrix_);
  }
}

// dense_cholesky_ <- the Cholesky factors of dense_matrix_ as it is; false where a pivot is
// not positive.
bool RigidCluster::factor_dense_cholesky() {
  dense_cholesky_ = dense_matrix_;
  cholesky_inverse_diagonal_.resize(dense_cholesky_.rows());
  return small_cholesky::factor(dense_cholesky_.data(), static_cast<int>(dense_cholesky_.rows()), cholesky_inverse_diagonal_.data());
}

// In the permuted numbering: y <- S_eps^-1 y (each column); S^-1 y where S is not shifted.
template <class X>
void RigidCluster::solve_shifted(X& y) const {
  if (dense_ && dense_factors_ == DenseFactors::cholesky) {
    for (Eigen::Index c = 0; c < y.cols(); ++c)
      small_cholesky::solve(dense_cholesky_.data(), static_cast<int>(y.rows()), cholesky_inverse_diagonal_.data(), y.col(c).data());
  } else if (dense_)
    y = dense_ldlt_.solve(y);
  else
    y = sparse_ldlt_->solve(y);
}

// Iterated regularisation (augmented-Lagrangian style): x <- x + S_eps^-1 (b - S x) a few
// times removes the bias of eps where S is regular, while where S is (nearly) singular the
// correction stays bounded by 1/eps. Each column of x on its own; rhs, permuted and
// residual are scratch of x's shape.
template <class X>
void RigidCluster::refined_solve(X& x, X& rhs, X& permuted, X& residual) const {
  const Eigen::Index m = x.rows();
  rhs.resize(m, x.cols());
  for (Eigen::Index r = 0; r < m; ++r) rhs.row(position_[static_cast<std::size_t>(r)]) = x.row(r);
  permuted = rhs;
  solve_shifted(permuted);
  for (int k = 0; k < (shifted_ ? refinements : 0); ++k) {
    if (dense_)
      residual.noalias() = dense_matrix_.selfadjointView<Eigen::Upper>() * permuted;
    else
      residual.noalias() = sparse_matrix_.selfadjointView<Eigen::Upper>() * permuted;
    for (Eigen::Index r = 0; r < m; ++r) {
      const Eigen::Index p = position_[static_cast<std::size_t>(r)];
      residual.row(p) = rhs.row(p) - residual.row(p) + shift_[static_cast<std::size_t>(r)] * permuted.row(p);
    }
    solve_shifted(residual);
    permuted += residual;
  }
  for (Eigen::Index r = 0; r < m; ++r) x.row(r) = permuted.row(position_[static_cast<std::size_t>(r)]);
}

void RigidCluster::solve(Eigen::VectorXd& x) const { refined_solve(x, rhs_, permuted_, residual_); }

void RigidCluster::solve(Eigen::MatrixXd& x) const {
  refined_solve(x, rhs_columns_, permuted_columns_, residual_columns_);
}

void RigidCluster::wrenches(const Eigen::Ref<const Eigen::VectorXd>& lambda, std::vector<Vector6d>& out) const {
  out.assign(bodies_.size(), Vector6d::Zero());
  for (int r = 0; r < rows_count_; ++r)
    for (int side = 0; side < 2; ++side)
      if (const int b = slot(r, side); b >= 0) out[static_cast<std::size_t>(b)] += lambda[r] * part(r, side);
}

void RigidCluster::motion(const Eigen::Ref<const Eigen::VectorXd>& lambda, std::vector<Vector6d>& out) const {
  wrenches(lambda, out);
  for (std::size_t b = 0; b < out.size(); ++b) out[b] = weighted(static_cast<int>(b), out[b]);
}

}  // namespace mbsflow
