#pragma once
// A multibody system as what a stepper integrates: its rhs, the sparsity of its Jacobian
// (the implicit methods factor it sparse), the analytic Jacobian where the model has one
// and `jacobian` is "auto" (else the methods difference by the pattern's colouring), and
// after every step the renormalised quaternions and prescribed motions.
#include <memory>

#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "mbsflow/runtime/eliminable.hpp"

namespace mbsflow {

inline StepperSystem stepper_system(MultibodySystem& sys, const std::string& jacobian = "auto") {
  StepperSystem s;
  if (jacobian == "auto" && sys.has_analytic_jacobian())
    s.jacobian = [&sys](double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac) { sys.jacobian(t, y, jac); };
  s.size = sys.dimension();
  s.rhs = [&sys](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { sys.rhs(t, y, dydt); };
  // A copy shares the compiled model and has its own workspace (260 bytes per body).
  s.another_rhs = [&sys]() -> StepperSystem::Rhs {
    auto copy = std::make_shared<MultibodySystem>(sys);
    return [copy](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { copy->rhs(t, y, dydt); };
  };
  s.after_step = [&sys](double t, Eigen::VectorXd& y) { sys.after_step(t, y); };
  s.sparsity = [&sys] { return sys.jacobian_pattern(); };
  s.eliminable = eliminable_unknowns(sys.layout());
  s.describe = [&sys](Eigen::Index i) { return describe_unknown(sys.model(), i); };
  return s;
}

}  // namespace mbsflow
