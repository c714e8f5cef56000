// The "tirk" stepper: triangularised implicit Runge-Kutta (TirkIntegrator), Newton-type
// triangular iteration (PTIRK). variant names the tableau (default radau3).
#include "mbsflow/methods/tirk_integrator.hpp"
#include "stepper_registry.hpp"
#include "implicit_stepper.hpp"

namespace mbsflow {
namespace {

class TirkStepper final : public ImplicitStepper<TirkIntegrator, TirkSettings> {
 public:
  TirkStepper(const StepperSystem& s, const StepperSettings& o) : ImplicitStepper(s, o) {
    if (!o.variant.empty()) settings_.tableau = o.variant;
    rk_tableau(settings_.tableau);  // InputError for an unknown tableau
    integrator_ = std::make_unique<TirkIntegrator>(problem_, settings_, s.after_step);
  }
  void dense(double t, Eigen::VectorXd& out) const override { integrator_->dense(t, out); }
};

}  // namespace

std::unique_ptr<Stepper> make_tirk_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<TirkStepper>(s, o);
}

}  // namespace mbsflow
