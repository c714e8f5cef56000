#pragma once
// What the colloc and tirk steppers share: the problem they hand their integrator (its
// t0, y0 and t_end set at every start), the settings, restarts that keep the step size,
// and the counters.
#include <memory>

#include "mbsflow/methods/step_grid.hpp"
#include "stepper_system.hpp"

namespace mbsflow {

// Integrator: BlockIntegrator or TirkIntegrator (begin, advance, t, y, next_step, stats).
template <class Integrator, class Settings>
class ImplicitStepper : public Stepper {
 public:
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
    if (!integrator_->advance()) {
      // Nothing left to integrate: the stretch began within rounding of t_end. That is the
      // end; without this done() stayed false and the caller stepped for ever.
      t_ = t_end_;
      return;
    }
    t_previous_ = t_;
    // A step that ends within rounding of t_end (ten steps of 0.1 make 0.9999999999999999)
    // is the last, as the integrator will find at its next advance: done() says so now, so
    // the caller does not take it for a step between others (a checkpoint after it, an
    // extra call).
    t_ = reached_end(integrator_->t(), t_end_) ? t_end_ : integrator_->t();
    y_ = integrator_->y();
    count();
  }
  double next_step() const override { return integrator_->next_step(); }

 protected:
  // The problem's current stretch, the step a restart begins with, then the integrator's
  // state. Dense output comes back with the next step.
  void save_method(StateWriter& out) const override {
    out.real(problem_.t0);
    out.real(problem_.t_end);
    out.vector(problem_.y0);
    out.real(settings_.initial_step);
    out.flag(started_);
    integrator_->save(out);
  }
  void restore_method(StateReader& in) override {
    problem_.t0 = in.real();
    problem_.t_end = in.real();
    problem_.y0 = in.vector(problem_.size);
    settings_.initial_step = in.real();
    started_ = in.flag();
    integrator_->restore(in);
  }

 public:
  void set_next_step(double h) override { settings_.initial_step = h; }

 protected:
  // The settings every implicit method takes from StepperSettings.
  ImplicitStepper(const StepperSystem& s, const StepperSettings& o) : problem_(problem_of(s)) {
    check_system(s);
    settings_.rtol = o.rtol;
    settings_.atol = o.atol;
    settings_.rtols = o.rtols;
    settings_.atols = o.atols;
    settings_.threads = o.threads;
    settings_.initial_step = o.step;
    settings_.finite_difference_jacobian = !s.jacobian;
    settings_.linear_solver = linear_solver_from_string(o.linear_solver);
    if (o.fixed_step) {
      if (!(o.step > 0)) throw InputError("a fixed-step run needs a positive step");
      settings_.fixed_step = o.step;
      settings_.max_iterations = 100;  // no step to shorten: the iteration may take longer to converge
    }
  }
  void count() {
    const auto& st = integrator_->stats();
    stats_.accepted = st.accepted;
    stats_.rejected = st.rejected;
    stats_.evaluations = st.rhs_evaluations;
    stats_.jacobians = st.jacobians;
    stats_.factorizations = st.factorizations;
  }

  OdeProblem problem_;
  Settings settings_;
  std::unique_ptr<Integrator> integrator_;

 private:
  bool started_ = false;
};

}  // namespace mbsflow
