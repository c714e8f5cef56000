#pragma once
// The Jacobian df/dy of a problem: from the problem when it has one, else by forward
// differences, perturbing together the columns that share no row (Curtis, Powell & Reid),
// so a banded or sparse system needs a few evaluations instead of one per column.
#include <Eigen/SparseCore>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

// Greedy colouring of the columns of a pattern: columns of one colour have no row in
// common. Returns the colour of each column (0-based).
std::vector<int> colour_columns(const Eigen::SparseMatrix<double>& pattern);

// max_i sum_j |J_ij|: the Lipschitz constant of a linear f in the max norm.
double infinity_norm(const Eigen::SparseMatrix<double>& j);

class JacobianEvaluator {
 public:
  // finite_differences forces differences even when the problem has a Jacobian.
  JacobianEvaluator(const OdeProblem& problem, bool finite_differences);
  // J at (t, y), with f = f(t, y) already known; counts the extra evaluations of f.
  const Eigen::SparseMatrix<double>& evaluate(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& f,
                                              long& rhs_evaluations);
  bool uses_differences() const { return differences_; }
  // The colours of the pattern: the evaluations of f one Jacobian by differences takes.
  int colours() const { return colours_; }

 private:
  const OdeProblem& problem_;
  bool differences_;
  Eigen::SparseMatrix<double> jac_, pattern_;
  std::vector<int> colour_;
  int colours_ = 0;
};

}  // namespace mbsflow
