#include "mbsflow/runtime/simulation.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "mbsflow/graph/error.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "sink_runner.hpp"
#include "step_grid.hpp"

namespace mbsflow {
namespace {

using Clock = std::chrono::steady_clock;

void check(const MultibodySystem& sys, const Eigen::VectorXd& y, double t, const RunOptions& o) {
  if (auto d = find_divergence(sys.layout(), y)) throw RunError(divergence_message(sys.model(), *d, t, o.method, o.step));
  check_stop(o, t);
}

void run_rk4(MultibodySystem& sys, const RunOptions& o, ResultSink* sink, RunSummary& out, Eigen::VectorXd& y) {
  Rk4 rk(sys.dimension());
  const StepGrid grid = step_grid(o.t_start, o.t_end, o.step);
  const long n = grid.steps;
  double t = o.t_start;
  for (long k = 1; k <= n; ++k) {
    const double t_next = grid.time(k);
    rk.step(sys, t, t_next - t, y);
    sys.after_step(t_next, y);
    t = t_next;
    check(sys, y, t, o);
    if (sink && (k % o.output_every == 0 || k == n)) emit(sys, sink, t, y, out);
    if (o.progress && (k & 15) == 0) o.progress(t, k);
  }
  out.steps = n;
  out.evaluations = n * Rk4::evaluations_per_step;
}

void run_dopri5(MultibodySystem& sys, const RunOptions& o, ResultSink* sink, RunSummary& out, Eigen::VectorXd& y) {
  Dopri5Settings s;
  s.rtol = o.rtol;
  s.atol = o.atol;
  Dopri5 dp(sys.dimension(), s);
  const double dt_out = o.step * o.output_every;
  long next_out = 1;
  double t = o.t_start, h = o.step;
  Eigen::VectorXd dense(sys.dimension());
  while (t < o.t_end) {
    h = std::min(h, o.t_end - t);
    double taken = 0.0;
    if (!dp.step(sys, t, h, y, taken)) throw RunError(step_collapsed_message(h, t, o.rtol));
    const double t_new = landed_time(t, taken, o.t_end);
    // Snapshots on the uniform output grid inside this step, from the dense output.
    while (sink) {
      const double t_out = o.t_start + static_cast<double>(next_out) * dt_out;
      if (t_out > t_new || t_out >= o.t_end) break;
      dp.dense(t_out, dense);
      sys.after_step(t_out, dense);
      emit(sys, sink, t_out, dense, out);
      ++next_out;
    }
    sys.after_step(t_new, y);
    dp.invalidate();
    t = t_new;
    check(sys, y, t, o);
    if (o.progress && (dp.stats().accepted & 15) == 0) o.progress(t, dp.stats().accepted);
  }
  if (sink) emit(sys, sink, t, y, out);
  out.steps = dp.stats().accepted;
  out.rejected = dp.stats().rejected;
  out.evaluations = dp.stats().evaluations;
}

}  // namespace

RunOptions options_from_model(const Model& model) {
  RunOptions o;
  const SimulationSettings& s = model.simulation;
  o.method = s.method;
  o.t_start = s.t_start;
  o.t_end = s.t_end;
  o.step = s.step ? *s.step : estimate_stable_step(model).step;
  o.output_every = s.output_every;
  o.rtol = s.rtol;
  o.atol = s.atol;
  return o;
}

RunSummary run_simulation(MultibodySystem& sys, const RunOptions& o, ResultSink* sink) {
  check_options(o);
  RunSummary out;
  const auto start = Clock::now();
  Eigen::VectorXd y = sys.initial_state();
  if (sink) sink->begin(sys);
  run_with_sink(sink, out, [&] {
    if (sink) emit(sys, sink, o.t_start, y, out);
    if (o.method == Method::rk4)
      run_rk4(sys, o, sink, out, y);
    else
      run_dopri5(sys, o, sink, out, y);
  });
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  return out;
}

}  // namespace mbsflow
