#include "mbsflow/runtime/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "run_loop.hpp"
#include "sink_runner.hpp"
#include "multibody_stepper.hpp"

namespace mbsflow {
namespace {

using Clock = std::chrono::steady_clock;

// A whole model's stepper as an advancer: one step each, then the snapshots that fall due
// (a fixed-step method every output_steps(o) steps and at the end; an adaptive one on the
// uniform grid from its dense output, then at the end). `next` is where it goes on: the
// index of the next fixed step, or of the next output time on the grid; a checkpoint
// keeps it with the stepper's state.
class StepperAdvancer final : public Advancer {
 public:
  StepperAdvancer(const MultibodySystem& sys, Stepper& stepper, const RunOptions& o)
      : stepper_(stepper), o_(o), adaptive_(stepper_entry(o.method).adaptive), every_(output_steps(o)),
        dense_(adaptive_ ? sys.dimension() : 0) {}

  bool done() const override { return stepper_.done(); }
  void advance(RunObserver& to) override {
    stepper_.step();
    const double t = stepper_.t();
    if (adaptive_ && to.wants_dense())
      next_ = dense_outputs(o_, next_, t, [&](long k, double t_out) {
        stepper_.dense(t_out, dense_);
        to.dense(k, t_out, dense_);
      });
    const long steps = adaptive_ ? stepper_.stats().accepted : next_++;
    const bool snapshot = stepper_.done() || (!adaptive_ && steps % every_ == 0);
    to.step_done(steps, t, snapshot ? steps : -1);
  }
  void save(StateWriter& w) override {
    w.integer(next_);
    stepper_.save(w);
  }
  double restore(StateReader& in) {
    next_ = in.integer(1, INT64_MAX);
    stepper_.restore(in);
    return stepper_.t();
  }

 private:
  Stepper& stepper_;
  const RunOptions& o_;
  bool adaptive_;
  int every_;
  long next_ = 1;
  Eigen::VectorXd dense_;
};

}  // namespace

RunOptions options_from_model(const Model& model, std::optional<double> stable_step) {
  RunOptions o;
  const SimulationSettings& s = model.simulation;
  const double stable = s.step ? 0.0 : stable_step ? *stable_step : estimate_stable_step(model).step;
  // No method named: RK4 where a step is given or a joint gives a stable one, else an
  // adaptive method (a pendulum on a rigid revolute has no stiffness to take a step from).
  // Beams are stiff (a steel element's axial and torsion modes lie far above its bending):
  // tirk unless a step is given.
  o.method = s.method                              ? *s.method
             : !model.beams.empty() && !s.step     ? Method::tirk
             : s.step || std::isfinite(stable)     ? Method::rk4
                                                   : Method::dopri5;
  o.method_chosen = !s.method;
  o.variant = s.variant;
  o.t_start = s.t_start;
  o.t_end = s.t_end;
  const bool adaptive = stepper_entry(o.method).adaptive;
  o.output_every = s.output_every.value_or(1);
  if (s.step) {
    o.step = *s.step;
  } else {
    o.step_given = false;
    o.step = stable;
    // Nothing stiff to estimate from (rigid joints only, say): an adaptive method starts
    // with a step of one output interval, or a thousandth of the run, and adapts.
    if (adaptive && !std::isfinite(o.step))
      o.step = s.output_interval ? *s.output_interval : (s.t_end - s.t_start) / 1000.0;
    if (s.output_interval && !adaptive && std::isfinite(o.step))  // fit a whole number of steps into it
      o.step = *s.output_interval / std::ceil(*s.output_interval / o.step * (1.0 - 1e-12));
  }
  if (s.output_interval)
    o.output_interval = *s.output_interval;
  else if (adaptive && !s.step)
    o.output_interval = o.output_every * (s.t_end - s.t_start) / 1000.0;
  else if (!adaptive && !s.output_every && std::isfinite(o.step) && o.step > 0.0)
    // About a thousand snapshots, on the grid of whole steps: the step stays as it is.
    o.output_every = static_cast<int>(std::clamp(std::ceil((s.t_end - s.t_start) / o.step / 1000.0 - 1e-9), 1.0, 1e9));
  o.rtol = s.rtol;
  o.atol = s.atol;
  if (!std::isfinite(o.step))
    throw InputError(model.name + ": " + method_name(o.method) + " needs a step, and no compliant joint gives one to "
                     "estimate from; give {step}, or leave out {method} (an adaptive method is then chosen), or "
                     "{method=dopri5}");
  return o;
}

RunSummary run_simulation(MultibodySystem& sys, const RunOptions& o, ResultSink* sink) {
  check_options(o);
  const StepperEntry& entry = stepper_entry(o.method);
  Eigen::VectorXd y = sys.initial_state();
  const StepperSystem system = stepper_system(sys, o.jacobian);
  std::unique_ptr<Stepper> stepper = entry.make(system, stepper_settings(o));
  stepper->start(o.t_start, y, o.t_end);
  phase_done(o, "set up the method");
  // Like run_partitioned's, the clock starts once the stepper and its workspace are set up.
  const auto start = Clock::now();
  StepperAdvancer advancer(sys, *stepper, o);
  LocalRun::Hooks hooks;
  hooks.check = [&](double t) { check_diverged(sys, stepper->y(), t, o); };
  hooks.state = [&](Eigen::VectorXd& x) { x = stepper->y(); };
  hooks.restore = [&](StateReader& in) { return advancer.restore(in); };
  hooks.progress_every = 16;
  LocalRun run("simulation", o, &sys, sink, std::move(hooks));
  run.begin();
  run.run([&] { return y; }, [&] { drive(advancer, run); });
  phase_done(o, sink ? "steps, and the results written" : "steps", RunPhase::steps);
  RunSummary& out = run.out;
  out.steps = stepper->stats().accepted;
  out.rejected = stepper->stats().rejected;
  out.evaluations = stepper->stats().evaluations;
  out.jacobians = stepper->stats().jacobians;
  out.factorizations = stepper->stats().factorizations;
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = stepper->y();
  return std::move(out);
}

}  // namespace mbsflow
