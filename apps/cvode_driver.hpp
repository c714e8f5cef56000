#pragma once
// SUNDIALS CVODE (BDF with Newton iterations) on an OdeProblem: the peer that the benchmarks
// run beside mbsflow's implicit methods, on the same right-hand side and the same Jacobian
// (the problem's own, else mbsflow's coloured finite differences over its sparsity).
#include <functional>
#include <string>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow::cli {

enum class CvodeLinearSolver { dense, band, klu };
const char* to_string(CvodeLinearSolver s);

struct CvodeOutcome {
  bool ok = false;
  double seconds = 0;
  long steps = 0, evaluations = 0, jacobians = 0, setups = 0;  // setups: Newton matrices factorised
  std::string note;                                            // why it stopped early
};

// From p.t0 to p.t_end at tolerances rtol, atol. With output times, on_output(t, y) sees
// CVODE's interpolated solution at each of them; without, the solution after every step.
// atols (one per equation), when given, replaces the scalar atol. projection, when given,
// puts the state of every accepted step back on the problem's manifold (CVODE's own
// projection; a multibody model's after_step, as mbsflow's steppers do).
CvodeOutcome run_cvode(const OdeProblem& p, double rtol, double atol, CvodeLinearSolver solver,
                       const std::vector<double>& outputs, const std::function<void(double t, const double* y)>& on_output,
                       const Eigen::VectorXd& atols = {},
                       const std::function<void(double t, Eigen::VectorXd& y)>& projection = {});

}  // namespace mbsflow::cli
