#pragma once
// A StepperSystem seen as the methods' OdeSystem (dimension(), rhs()) and as an
// OdeProblem for the implicit integrators.
#include <memory>
#include <mutex>

#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

struct StepperOde {
  const StepperSystem& s;
  Eigen::Index dimension() const { return s.size; }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { s.rhs(t, y, dydt); }
};

// The problem the implicit integrators read; start() sets t0, y0 and t_end. They evaluate
// stages (and finite-difference columns) from several flow-graph nodes at once, but a
// StepperSystem's rhs and Jacobian are called by one thread at a time (a multibody system
// and a loose submodel work in their own scratch), so the calls are serialised here, the
// Jacobian's with the rhs's.
inline OdeProblem problem_of(const StepperSystem& s) {
  auto busy = std::make_shared<std::mutex>();
  auto rhs = [f = s.rhs, busy](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    std::lock_guard lock(*busy);
    f(t, y, dydt);
  };
  OdeProblem p = make_ode_problem("system", 0.0, 1.0, Eigen::VectorXd::Zero(s.size), rhs);
  if (s.jacobian)
    p.jacobian = [j = s.jacobian, busy](double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac) {
      std::lock_guard lock(*busy);
      j(t, y, jac);
    };
  p.describe = s.describe;
  if (s.sparsity) p.sparsity = s.sparsity();
  p.eliminable = s.eliminable;
  return p;
}

inline void check_system(const StepperSystem& s) {
  if (s.size < 1 || !s.rhs) throw InputError("a stepper needs a system with a size and a right-hand side");
}

}  // namespace mbsflow
