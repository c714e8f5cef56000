// The "rk4" stepper: classic Runge-Kutta with fixed steps on the grid t_start + k h (the
// last step shortened to land on t_end), the arithmetic of mbsflow::Rk4.
#include "mbsflow/methods/rk4.hpp"

#include <cstdint>

#include "mbsflow/methods/step_grid.hpp"
#include "cubic_hermite.hpp"
#include "stepper_registry.hpp"
#include "stepper_system.hpp"

namespace mbsflow {
namespace {

class Rk4Stepper final : public Stepper {
 public:
  Rk4Stepper(const StepperSystem& s, const StepperSettings& o) : sys_(s), h_(o.step), rk_(s.size) {
    check_system(s);
    if (!(h_ > 0.0)) throw InputError("rk4 needs a positive step");
  }
  void start(double t, const Eigen::VectorXd& y, double t_end) override {
    grid_ = step_grid(t, t_end, h_);
    k_ = 0;
    slopes_for_ = -1;
    t_ = t_previous_ = t;
    t_end_ = t_end;
    y_ = y;
    y_previous_ = y;  // its memory now, before the first step
  }
  void step() override {
    if (done()) return;
    y_previous_ = y_;
    const double t_next = grid_.time(k_ + 1);
    StepperOde ode{sys_};
    rk_.step(ode, t_, t_next - t_, y_);
    if (sys_.after_step) sys_.after_step(t_next, y_);
    t_previous_ = t_;
    t_ = t_next;
    ++k_;
    ++stats_.accepted;
    stats_.evaluations += Rk4::evaluations_per_step;
  }
  // Cubic Hermite between the step's ends (third order, for events and output between
  // steps). The slopes at the ends cost two evaluations, made only when dense output is
  // asked for in a step (RK4's own stages are not kept).
  void dense(double t, Eigen::VectorXd& out) const override {
    if (slopes_for_ != k_) {
      f_previous_.resize(y_.size());
      f_.resize(y_.size());
      sys_.rhs(t_previous_, y_previous_, f_previous_);
      sys_.rhs(t_, y_, f_);
      stats_.evaluations += 2;
      slopes_for_ = k_;
    }
    cubic_hermite(t_previous_, y_previous_, f_previous_, t_, y_, f_, t, out);
  }

 protected:
  void save_method(StateWriter& out) const override {
    out.text("rk4");
    out.real(grid_.t_start);
    out.real(grid_.t_end);
    out.real(grid_.h);
    out.integer(grid_.steps);
    out.integer(k_);
    out.vector(y_previous_);
  }
  void restore_method(StateReader& in) override {
    in.expect("rk4");
    grid_.t_start = in.real();
    grid_.t_end = in.real();
    grid_.h = in.real();
    grid_.steps = in.integer(0, INT64_MAX);
    k_ = in.integer(0, grid_.steps);
    y_previous_ = in.vector();
    if (y_previous_.size() != 0 && y_previous_.size() != y_.size()) in.fail("rk4: the previous state has the wrong size");
    slopes_for_ = -1;  // dense output recomputes the end slopes: rhs is a function of (t, y)
  }

 private:
  const StepperSystem& sys_;
  double h_;
  Rk4 rk_;
  StepGrid grid_;
  long k_ = 0;
  Eigen::VectorXd y_previous_;
  mutable Eigen::VectorXd f_previous_, f_;  // the slopes at the ends of step slopes_for_
  mutable long slopes_for_ = -1;
};

}  // namespace

std::unique_ptr<Stepper> make_rk4_stepper(const StepperSystem& s, const StepperSettings& o) {
  return std::make_unique<Rk4Stepper>(s, o);
}

}  // namespace mbsflow
