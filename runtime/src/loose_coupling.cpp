#include "mbsflow/runtime/loose_coupling.hpp"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "loose_part.hpp"
#include "mbsflow/graph/error.hpp"
#include "schedules.hpp"
#include "sink_runner.hpp"
#include "step_grid.hpp"

namespace mbsflow {
namespace {

using loose::LoosePart;
using Clock = std::chrono::steady_clock;

}  // namespace

void check_loose_options(const LooseOptions& lo) {
  if (!(lo.macro_step > 0.0) || !std::isfinite(lo.macro_step)) throw InputError("--macro-step: must be a positive time");
  if (lo.extrapolation < 0 || lo.extrapolation > 2) throw InputError("--extrapolation: must be 0, 1 or 2");
  if (lo.max_lag < 0) throw InputError("--max-lag: must be >= 0");
  if (lo.max_lag > 0 && lo.coupling_tol > 0.0) throw InputError("--max-lag: needs a fixed macro step (not with --coupling-tol)");
}

RunSummary run_loose(const Model& model, const Decomposition& d, const RunOptions& o, const LooseOptions& lo,
                     ResultSink* sink, LooseStats* stats) {
  check_options(o);
  check_loose_options(lo);
  const int threads = lo.threads > 0 ? lo.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  std::vector<std::unique_ptr<LoosePart>> parts;
  for (const Submodel& s : d.submodels) parts.push_back(std::make_unique<LoosePart>(model, s, o, lo.extrapolation, lo.max_lag));
  MultibodySystem whole(model);
  const StateLayout& global = whole.layout();
  RunSummary out;
  LooseStats local_stats;
  LooseStats& st = stats ? *stats : local_stats;
  const auto start = Clock::now();
  Eigen::VectorXd y = whole.initial_state();
  if (sink) sink->begin(whole);
  // One flow-graph node per submodel per macro step, all independent within the step.
  double t0 = 0.0, t1 = 0.0;
  Scheduler schedule(d, 1, 1, [&](std::size_t p, int, int, Half) { parts[p]->integrate(t0, t1); });
  const bool adaptive = lo.coupling_tol > 0.0;
  const double order = lo.extrapolation + 1.0;
  const StepGrid grid = step_grid(o.t_start, o.t_end, o.step);
  run_with_sink(sink, out, [&] {
    if (sink) emit(whole, sink, o.t_start, y, out);
    for (auto& p : parts) p->make_past(o.t_start, lo.macro_step);
    for (int j = 1; j <= lo.extrapolation; ++j)
      loose::copy_local_ghosts(parts, j, [j](const LoosePart& owner) -> const Eigen::VectorXd& {
        return owner.part.x[static_cast<std::size_t>(j)];
      });
    for (auto& p : parts) p->start(o.t_start, lo.macro_step);
    double t = o.t_start, H = lo.macro_step;
    long next_out = 1;
    while (t < o.t_end) {
      bool on_output = false;
      t0 = t;
      t1 = loose::next_macro_end(grid, o.output_every, next_out, t, H, &on_output);
      if (adaptive)
        for (auto& p : parts) p->save();
      arena.execute([&] { schedule.run(1); });
      for (auto& p : parts)
        if (auto dv = partitioned::check(p->part)) throw RunError(divergence_message(model, *dv, t1, o.method, o.step));
      // The owners' values at the macro-step end L steps back (this one for L = 0).
      for (auto& p : parts) p->keep(st.macro_steps + 1, t1);
      const long lagged = st.macro_steps + 1 - lo.max_lag;
      loose::CouplingError e;
      if (lagged >= 1) {
        loose::copy_local_ghosts(parts, 0, [lagged](const LoosePart& owner) -> const Eigen::VectorXd& { return owner.kept(lagged); });
        for (auto& p : parts) {
          const loose::CouplingError pe = p->error(p->kept_time(lagged));
          e.position = std::max(e.position, pe.position);
          e.velocity = std::max(e.velocity, pe.velocity);
        }
      }
      // Step-size factor from the error model e ~ H^(order).
      const double factor =
          adaptive ? std::clamp(0.9 * std::pow(lo.coupling_tol / std::max(e.position, 1e-300), 1.0 / order), 0.2, 2.0) : 1.0;
      if (adaptive && e.position > lo.coupling_tol) {  // too far off: back to t0 with a shorter macro step
        for (auto& p : parts) p->restore(st.macro_steps + 1);
        H = (t1 - t0) * factor;
        ++st.rejected;
        if (H < 1e-6 * lo.macro_step) {
          char buf[160];
          std::snprintf(buf, sizeof buf,
                        "coupling error %.3g m above --coupling-tol %.3g m even with a macro step of %.3g s at t = %.6g s",
                        e.position, lo.coupling_tol, t1 - t0, t0);
          throw RunError(buf);
        }
        continue;
      }
      for (auto& p : parts) {
        if (lagged >= 1) p->push(p->kept_time(lagged));
        partitioned::gather(p->part, global, y);
      }
      st.position_error.push_back(e.position);
      st.velocity_error.push_back(e.velocity);
      st.max_position_error = std::max(st.max_position_error, e.position);
      st.smallest_macro_step = st.macro_steps == 0 ? t1 - t0 : std::min(st.smallest_macro_step, t1 - t0);
      st.largest_macro_step = std::max(st.largest_macro_step, t1 - t0);
      ++st.macro_steps;
      if (on_output) {
        if (sink) emit(whole, sink, t1, y, out);
        ++next_out;
      }
      if (adaptive) H = on_output && factor >= 1.0 ? std::max(H, (t1 - t0) * factor) : (t1 - t0) * factor;
      t = t1;
      check_stop(o, t);
      if (o.progress) o.progress(t, st.macro_steps);
    }
  });
  for (const auto& p : parts) {
    out.steps = std::max(out.steps, p->steps);
    out.rejected += p->rejected;
    out.evaluations += p->evaluations;
  }
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  return out;
}

}  // namespace mbsflow
