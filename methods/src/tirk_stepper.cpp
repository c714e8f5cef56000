// The "tirk" stepper: triangularised implicit Runge-Kutta (TirkIntegrator), Newton-type
// triangular iteration (PTIRK). variant names the tableau (default radau3).
#include "mbsflow/methods/tirk_integrator.hpp"
#include "stepper_registry.hpp"
#include "stepper_system.hpp"

namespace mbsflow {
namespace {

class TirkStepper final : public Stepper {
 public:
  TirkStepper(const StepperSystem& s, const StepperSettings& o) : problem_(problem_of(s)) {
    check_system(s);
    if (!o.variant.empty()) settings_.tableau = o.variant;
    rk_tableau(settings_.tableau);  // InputError for an unknown tableau
    settings_.rtol = o.rtol;
    settings_.atol = o.atol;
    settings_.threads = o.threads;
    settings_.initial_step = o.step;
    settings_.finite_difference_jacobian = !s.jacobian;
    integrator_ = std::make_unique<TirkIntegrator>(problem_, settings_, s.after_step);
  }
  void start(double t, const Eigen::VectorXd& y, double t_end) override {
    problem_.t0 = t;
    problem_.t_end = t_end;
    problem_.y0 = y;
    if (started_) settings_.initial_step = integrator_->next_step();
    started_ = true;
    integrator_->begin();
    t_ = t_previous_ = t;
    t_end_ = t_end;
    y_ = y;
    count();
  }
  void step() override {
    if (!integrator_->advance()) return;
    t_previous_ = t_;
    t_ = integrator_->t();
    y_ = integrator_->y();
    count();
  }
  void dense(double t, Eigen::VectorXd& out) const override { integrator_->dense(t, out); }
  double next_step() const override { return integrator_->next_step(); }
  void set_next_step(double h) override { settings_.initial_step = h; }

 private:
  void count() {
    const TirkStats& st = integrator_->stats();
    stats_.accepted = st.accepted;
    stats_.rejected = st.rejected;
    stats_.evaluations = st.rhs_evaluations;
  }

  OdeProblem problem_;
  TirkSettings settings_;
  std::unique_ptr<TirkIntegrator> integrator_;
  bool started_ = false;
};

}  // namespace

std::unique_ptr<Stepper> make_tirk_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<TirkStepper>(s, o);
}

}  // namespace mbsflow
