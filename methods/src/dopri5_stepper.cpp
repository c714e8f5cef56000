// The "dopri5" stepper: Dormand-Prince 5(4) with the PI controller and Shampine's dense
// output (mbsflow::Dopri5), landing exactly on t_end.
#include "mbsflow/methods/dopri5.hpp"

#include <cstdio>

#include "mbsflow/methods/step_grid.hpp"
#include "stepper_registry.hpp"
#include "stepper_system.hpp"

namespace mbsflow {

std::string step_collapsed_message(double h, double t, double rtol) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "DOPRI5 step size fell to %.3g s at t = %.6g s: the model is too stiff for an explicit method "
                "at rtol %.3g; loosen {rtol} or check the model",
                h, t, rtol);
  return buf;
}

namespace {

Dopri5Settings dopri5_settings(const StepperSettings& o) {
  Dopri5Settings s;
  s.rtol = o.rtol;
  s.atol = o.atol;
  return s;
}

class Dopri5Stepper final : public Stepper {
 public:
  Dopri5Stepper(const StepperSystem& s, const StepperSettings& o)
      : sys_(s), rtol_(o.rtol), dp_(s.size, dopri5_settings(o)), h_(o.step) {
    check_system(s);
  }
  void start(double t, const Eigen::VectorXd& y, double t_end) override {
    t_ = t_previous_ = t;
    t_end_ = t_end;
    y_ = y;
    dp_.invalidate();  // the stored f(t, y) belongs to another state
    StepperOde ode{sys_};
    if (!(h_ > 0.0)) h_ = dp_.initial_step(ode, t, y_);
  }
  void step() override {
    if (done()) return;
    h_ = std::min(h_, t_end_ - t_);
    double taken = 0.0;
    StepperOde ode{sys_};
    if (!dp_.step(ode, t_, h_, y_, taken)) throw RunError(step_collapsed_message(h_, t_, rtol_));
    const double t_new = landed_time(t_, taken, t_end_);
    if (sys_.after_step) sys_.after_step(t_new, y_);
    dp_.invalidate();
    t_previous_ = t_;
    t_ = t_new;
    stats_.accepted = dp_.stats().accepted;
    stats_.rejected = dp_.stats().rejected;
    stats_.evaluations = dp_.stats().evaluations;
  }
  void dense(double t, Eigen::VectorXd& out) const override { dp_.dense(t, out); }
  double next_step() const override { return h_; }
  void set_next_step(double h) override { h_ = h; }

 protected:
  void save_method(StateWriter& out) const override {
    out.text("dopri5");
    out.real(h_);
    dp_.save(out);
  }
  void restore_method(StateReader& in) override {
    in.expect("dopri5");
    h_ = in.real();
    dp_.restore(in);
  }

 private:
  const StepperSystem& sys_;
  double rtol_;
  Dopri5 dp_;
  double h_;
};

}  // namespace

std::unique_ptr<Stepper> make_dopri5_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<Dopri5Stepper>(s, o);
}

}  // namespace mbsflow
