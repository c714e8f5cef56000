#pragma once
// A StepperSystem seen as the methods' OdeSystem (dimension(), rhs()) and as an
// OdeProblem for the implicit integrators.
#include <memory>
#include <mutex>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

struct StepperOde {
  const StepperSystem& s;
  Eigen::Index dimension() const { return s.size; }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { s.rhs(t, y, dydt); }
};

// Evaluators of a system's rhs for calls that may overlap, each with scratch of its own:
// a call takes a free one, or has another made when none is free. The evaluations are
// the system's, so the numbers do not depend on which one a call took.
class RhsPool {
 public:
  RhsPool(std::function<StepperSystem::Rhs()> make, std::shared_ptr<std::mutex> making)
      : make_(std::move(make)), making_(std::move(making)) {}
  void operator()(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    StepperSystem::Rhs f = take();
    struct Back {  // returned to the pool however the call ends
      RhsPool& pool;
      StepperSystem::Rhs& f;
      ~Back() {
        std::lock_guard lock(pool.free_mutex_);
        pool.free_.push_back(std::move(f));
      }
    } back{*this, f};
    f(t, y, dydt);
  }

 private:
  StepperSystem::Rhs take() {
    {
      std::lock_guard lock(free_mutex_);
      if (!free_.empty()) {
        StepperSystem::Rhs f = std::move(free_.back());
        free_.pop_back();
        return f;
      }
    }
    std::lock_guard lock(*making_);  // another_rhs reads the system that rhs and jacobian use
    return make_();
  }

  std::function<StepperSystem::Rhs()> make_;
  std::shared_ptr<std::mutex> making_;
  std::mutex free_mutex_;
  std::vector<StepperSystem::Rhs> free_;
};

// The problem the implicit integrators read; start() sets t0, y0 and t_end. They evaluate
// stages (and finite-difference columns) from several flow-graph nodes at once. A
// StepperSystem's rhs and Jacobian are called by one thread at a time (a multibody system
// and a loose submodel work in their own scratch): with another_rhs the stages go to a
// pool of evaluators; else the calls are serialised here, the Jacobian's with the rhs's.
inline OdeProblem problem_of(const StepperSystem& s) {
  auto busy = std::make_shared<std::mutex>();
  StepperSystem::Rhs rhs;
  if (s.another_rhs) {
    rhs = [pool = std::make_shared<RhsPool>(s.another_rhs, busy)](double t, const Eigen::VectorXd& y,
                                                                   Eigen::VectorXd& dydt) { (*pool)(t, y, dydt); };
  } else {
    rhs = [f = s.rhs, busy](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
      std::lock_guard lock(*busy);
      f(t, y, dydt);
    };
  }
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
