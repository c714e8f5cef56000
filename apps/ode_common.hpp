#pragma once
// What the two method families of `mbsflow ode` share: the arguments, the recording of the
// accepted points with their error, and the results file.
#include <string>
#include <utility>
#include <vector>

#include "mbsflow/io/ode_results.hpp"
#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/shifted_solver.hpp"

namespace mbsflow::cli {

struct OdeArgs {
  std::string problem, method = "colloc", tableau = "radau3", iteration, jacobian = "auto", solver = "auto", output;
  std::string nodes;  // colloc: radau or equidistant; empty: radau unless --m > 1 or --order is given
  long n = 1000;
  int s = 3, m = 1, order = 0, threads = 0, iterations = 0, inner = 3;
  double tol = 1e-6, fixed_step = 0, initial_step = 0;
  std::vector<double> rtols, atols;  // one value, or one per equation; empty: --tol (atol: --tol times the problem's absolute scale)
  bool stability_table = false, quiet = false;
  bool output_given = false, force = false;  // -o "" is refused; --force: -o may replace any regular file
};

// The accepted points of a run: the error against the exact solution (all components) and,
// for the results file, up to 9 components spread over the state.
class OdeRecorder {
 public:
  OdeRecorder(const OdeProblem& p, bool keep);
  void add(double t, const Eigen::VectorXd& y);
  double max_error() const { return max_error_; }
  // Warns on stderr about the components whose size stayed below their absolute tolerance
  // at every accepted point (methods/uncontrolled.hpp). atols: per component, or empty.
  void warn_uncontrolled(double atol, const Eigen::VectorXd& atols) const;
  // Writes the file (when one was asked for) and says where it is and how to plot it.
  void write(const std::string& path, std::vector<BlockStepRecord> steps, std::vector<std::pair<std::string, std::string>> texts,
             std::vector<std::pair<std::string, double>> numbers, bool quiet);

 private:
  const OdeProblem& p_;
  bool keep_;
  OdeResults out_;
  double max_error_ = 0;
  Eigen::VectorXd largest_;  // per component, the largest |y| at an accepted point
};

// A tolerance of the command line: one value (scalar) or one per equation (vector).
void set_tolerance(const std::vector<double>& given, double& scalar, Eigen::VectorXd& vector);

// The settings both integrators share, from the arguments (the linear solver's name is
// checked by the caller, which turns InputError into an input error).
template <class Settings>
void apply_common_options(const OdeArgs& a, const OdeProblem& p, Settings& s) {
  s.linear_solver = linear_solver_from_string(a.solver);
  s.finite_difference_jacobian = a.jacobian == "differences" || a.jacobian == "fd";
  s.rtol = s.atol = a.tol;
  if (a.atols.empty() && p.absolute_scale.size() > 0) s.atols = a.tol * p.absolute_scale;
  set_tolerance(a.rtols, s.rtol, s.rtols);
  set_tolerance(a.atols, s.atol, s.atols);
  s.fixed_step = a.fixed_step;
  s.initial_step = a.initial_step;
  s.threads = a.threads;
}

// Prints the end point's error against the problem's published reference value, when it
// has one (and no exact solution).
void report_end_error(const OdeProblem& p, const Eigen::VectorXd& y_end);

int run_tirk(const OdeArgs& a);
int describe_tableau(const std::string& name);

}  // namespace mbsflow::cli
