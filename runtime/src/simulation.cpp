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
#include "sink_runner.hpp"
#include "multibody_stepper.hpp"

namespace mbsflow {
namespace {

using Clock = std::chrono::steady_clock;

void check(const MultibodySystem& sys, const Eigen::VectorXd& y, double t, const RunOptions& o) {
  check_diverged(sys, y, t, o);
  check_stop(o, t);
}

// Checkpoints of the loop: between two steps, `next` is the index of the next fixed step
// or of the next output on the grid, then the stepper's state.
void save_point(const Checkpointing& c, ResultSink* sink, const Stepper& stepper, Method method, long next,
                const RunSummary& out) {
  StateWriter w = checkpoint_head("simulation", method, sink, out);
  w.integer(next);
  stepper.save(w);
  c.write(w.take());
}

// Restores the stepper and `out` from a state save_point wrote; returns `next`.
long restore_point(const Checkpointing& c, ResultSink* sink, const MultibodySystem& sys, Stepper& stepper, Method method,
                   RunSummary& out) {
  StateReader in(c.resume, c.resume_from);
  const std::string results = read_checkpoint_head(in, "simulation", method, out);
  const long next = in.integer(1, INT64_MAX);
  stepper.restore(in);
  out.resumed_at = stepper.t();
  resume_results(in, c, sink, sys, results, out);
  return next;
}

// The loop over a whole model's stepper: after every step the snapshots that fall due (a
// fixed-step method every output_steps(o) steps and at the end; an adaptive one on the
// uniform grid from its dense output, then at the end), the guards, progress and
// checkpoints. `next` is where the loop goes on: the index of the next fixed step, or of
// the next output time on the grid.
void run_steps(MultibodySystem& sys, Stepper& stepper, bool adaptive, const RunOptions& o, ResultSink* sink,
               RunSummary& out, long next) {
  const int every = output_steps(o);
  Eigen::VectorXd dense(adaptive ? sys.dimension() : 0);
  CheckpointTimer checkpoint(o.checkpoint);
  while (!stepper.done()) {
    stepper.step();
    const double t = stepper.t();
    if (adaptive && sink)
      next = dense_outputs(o, next, t, [&](long, double t_out) {
        stepper.dense(t_out, dense);
        sys.after_step(t_out, dense);
        emit(sys, sink, t_out, dense, out);
      });
    check(sys, stepper.y(), t, o);
    const long steps = adaptive ? stepper.stats().accepted : next++;
    if (!adaptive && sink && (steps % every == 0 || stepper.done())) emit(sys, sink, t, stepper.y(), out);
    if (o.progress && (steps & 15) == 0) o.progress(t, steps);
    if (!stepper.done() && checkpoint.due()) save_point(*o.checkpoint, sink, stepper, o.method, next, out);
  }
  if (adaptive && sink) emit(sys, sink, stepper.t(), stepper.y(), out);
}

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
  RunSummary out;
  Eigen::VectorXd y = sys.initial_state();
  const StepperSystem system = stepper_system(sys, o.jacobian);
  std::unique_ptr<Stepper> stepper = entry.make(system, stepper_settings(o));
  stepper->start(o.t_start, y, o.t_end);
  phase_done(o, "set up the method");
  // Like run_partitioned's, the clock starts once the stepper and its workspace are set up.
  const auto start = Clock::now();
  const bool resume = o.checkpoint && !o.checkpoint->resume.empty();
  const long next = resume ? restore_point(*o.checkpoint, sink, sys, *stepper, o.method, out) : 1;
  if (sink && !resume) sink->begin(sys);
  if (sink) phase_done(o, "start the results file");
  run_with_sink(sink, out, [&] {
    if (sink && !resume) emit(sys, sink, o.t_start, y, out);
    run_steps(sys, *stepper, entry.adaptive, o, sink, out, next);
  });
  phase_done(o, sink ? "steps, and the results written" : "steps", RunPhase::steps);
  out.steps = stepper->stats().accepted;
  out.rejected = stepper->stats().rejected;
  out.evaluations = stepper->stats().evaluations;
  out.jacobians = stepper->stats().jacobians;
  out.factorizations = stepper->stats().factorizations;
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = stepper->y();
  return out;
}

}  // namespace mbsflow
