#include "mbsflow/methods/jacobian.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mbsflow {

std::vector<int> colour_columns(const Eigen::SparseMatrix<double>& pattern) {
  const Eigen::Index n = pattern.cols();
  const Eigen::SparseMatrix<double, Eigen::RowMajor> rows = pattern;
  std::vector<int> colour(static_cast<std::size_t>(n), -1);
  std::vector<Eigen::Index> used_by(static_cast<std::size_t>(n) + 1, -1);  // colour -> last column that saw it
  for (Eigen::Index c = 0; c < n; ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(pattern, c); it; ++it)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator jt(rows, it.row()); jt; ++jt) {
        const int k = colour[static_cast<std::size_t>(jt.col())];
        if (k >= 0) used_by[static_cast<std::size_t>(k)] = c;
      }
    int k = 0;
    while (used_by[static_cast<std::size_t>(k)] == c) ++k;
    colour[static_cast<std::size_t>(c)] = k;
  }
  return colour;
}

JacobianEvaluator::JacobianEvaluator(const OdeProblem& problem, bool finite_differences)
    : problem_(problem), differences_(finite_differences || !problem.jacobian) {
  const Eigen::Index n = problem.size;
  if (problem.sparsity) {
    pattern_ = *problem.sparsity;
  } else {
    std::vector<Eigen::Triplet<double>> all;
    all.reserve(static_cast<std::size_t>(n * n));
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = 0; r < n; ++r) all.emplace_back(r, c, 1.0);
    pattern_.resize(n, n);
    pattern_.setFromTriplets(all.begin(), all.end());
  }
  pattern_.makeCompressed();
  jac_ = pattern_;  // the problem's Jacobian writes its values into this pattern too
  colour_ = colour_columns(pattern_);  // coloured also for an analytic Jacobian: colours() sizes its cost
  colours_ = colour_.empty() ? 0 : *std::max_element(colour_.begin(), colour_.end()) + 1;
}

const Eigen::SparseMatrix<double>& JacobianEvaluator::evaluate(double t, const Eigen::VectorXd& y,
                                                               const Eigen::VectorXd& f, long& rhs_evaluations) {
  if (!differences_) {
    problem_.jacobian(t, y, jac_);
    return jac_;
  }
  const Eigen::Index n = problem_.size;
  const double root_eps = std::sqrt(std::numeric_limits<double>::epsilon());
  Eigen::VectorXd yp = y, fp(n), delta(n);
  for (int k = 0; k < colours_; ++k) {
    for (Eigen::Index c = 0; c < n; ++c)
      if (colour_[static_cast<std::size_t>(c)] == k) {
        delta(c) = root_eps * std::max(1e-5, std::abs(y(c)));
        yp(c) = y(c) + delta(c);
      }
    problem_.evaluate(t, yp, fp);
    ++rhs_evaluations;
    for (Eigen::Index c = 0; c < n; ++c) {
      if (colour_[static_cast<std::size_t>(c)] != k) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(jac_, c); it; ++it) it.valueRef() = (fp(it.row()) - f(it.row())) / delta(c);
      yp(c) = y(c);
    }
  }
  return jac_;
}

double infinity_norm(const Eigen::SparseMatrix<double>& j) {
  Eigen::VectorXd rows = Eigen::VectorXd::Zero(j.rows());
  for (Eigen::Index c = 0; c < j.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(j, c); it; ++it) rows(it.row()) += std::abs(it.value());
  return rows.size() ? rows.maxCoeff() : 0.0;
}

}  // namespace mbsflow
