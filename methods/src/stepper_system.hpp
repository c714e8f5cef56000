#pragma once
// A StepperSystem seen as the methods' OdeSystem (dimension(), rhs()) and as an
// OdeProblem for the implicit integrators.
#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

struct StepperOde {
  const StepperSystem& s;
  Eigen::Index dimension() const { return s.size; }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { s.rhs(t, y, dydt); }
};

// The problem the implicit integrators read; start() sets t0, y0 and t_end.
inline OdeProblem problem_of(const StepperSystem& s) {
  OdeProblem p = make_ode_problem("system", 0.0, 1.0, Eigen::VectorXd::Zero(s.size), s.rhs);
  p.jacobian = s.jacobian;
  p.sparsity = s.sparsity;
  return p;
}

inline void check_system(const StepperSystem& s) {
  if (s.size < 1 || !s.rhs) throw InputError("a stepper needs a system with a size and a right-hand side");
}

}  // namespace mbsflow
