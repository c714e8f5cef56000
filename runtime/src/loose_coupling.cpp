#include "mbsflow/runtime/loose_coupling.hpp"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <deque>
#include <memory>

#include "mbsflow/graph/error.hpp"
#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "partitioned_state.hpp"
#include "sink_runner.hpp"
#include "step_grid.hpp"
#include "schedules.hpp"

namespace mbsflow {
namespace {

using partitioned::Part;
using Clock = std::chrono::steady_clock;

// The exchanged samples: the global state at the last few macro-step ends, newest first.
struct History {
  std::deque<std::pair<double, Eigen::VectorXd>> samples;
  int order = 1;
  void add(double t, const Eigen::VectorXd& y) {
    samples.emplace_front(t, y);
    while (static_cast<int>(samples.size()) > order + 1) samples.pop_back();
  }
  // Lagrange weights at t over the samples held (fewer at the start: lower order).
  std::vector<double> weights(double t) const {
    const std::size_t n = samples.size();
    std::vector<double> w(n, 1.0);
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t m = 0; m < n; ++m)
        if (m != j) w[j] *= (t - samples[m].first) / (samples[j].first - samples[m].first);
    return w;
  }
};

// One body's 13 numbers extrapolated from the history into `out` (layout l, slot i); the
// quaternion renormalised.
void extrapolate_body(const History& h, const std::vector<double>& w, const StateLayout& global, int body,
                      const StateLayout& l, Eigen::Index slot, Eigen::VectorXd& out) {
  auto field = [&](Eigen::Index (StateLayout::*offset)(Eigen::Index) const, int n) {
    auto dst = out.segment((l.*offset)(slot), n);
    dst.setZero();
    for (std::size_t j = 0; j < w.size(); ++j) dst += w[j] * h.samples[j].second.segment((global.*offset)(body), n);
  };
  field(&StateLayout::position, 3);
  field(&StateLayout::orientation, 4);
  field(&StateLayout::velocity, 3);
  field(&StateLayout::angular_velocity, 3);
  out.segment<4>(l.orientation(slot)).normalize();
}

// A submodel's local system whose ghost bodies follow the extrapolation, whatever the
// integrator puts in their places; their derivatives are zero.
struct GhostedSystem {
  Part& part;
  const History& history;
  const StateLayout& global;
  Eigen::VectorXd work;

  Eigen::Index dimension() const { return part.system.dimension(); }
  void fill(double t, Eigen::VectorXd& y) const {
    const std::vector<double> w = history.weights(t);
    const StateLayout& l = part.system.layout();
    for (std::size_t g = 0; g < part.sub->ghosts.size(); ++g)
      extrapolate_body(history, w, global, part.sub->ghosts[g], l, part.own + static_cast<Eigen::Index>(g), y);
  }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    work = y;
    fill(t, work);
    part.system.rhs(t, work, dydt);
    const StateLayout& l = part.system.layout();
    const Eigen::Index ghosts = l.bodies - part.own;
    dydt.segment(l.position(part.own), 3 * ghosts).setZero();
    dydt.segment(l.orientation(part.own), 4 * ghosts).setZero();
    dydt.segment(l.velocity(part.own), 3 * ghosts).setZero();
    dydt.segment(l.angular_velocity(part.own), 3 * ghosts).setZero();
  }
};

// One submodel's integrator, kept from macro step to macro step.
struct Local {
  std::unique_ptr<Rk4> rk4;
  std::unique_ptr<Dopri5> dopri5;
  double h = 0.0;  // DOPRI5's next step
  long steps = 0, rejected = 0, evaluations = 0;
};

void integrate(Part& part, Local& local, GhostedSystem& sys, const RunOptions& o, double t0, double t1) {
  Eigen::VectorXd& y = part.x[0];
  if (local.rk4) {
    const StepGrid grid = step_grid(t0, t1, o.step);
    for (long k = 0; k < grid.steps; ++k) {
      local.rk4->step(sys, grid.time(k), grid.time(k + 1) - grid.time(k), y);
      part.system.after_step(grid.time(k + 1), y);
    }
    local.steps += grid.steps;
    local.evaluations += 4 * grid.steps;
    return;
  }
  Dopri5& dp = *local.dopri5;
  dp.invalidate();  // the ghosts moved on: the stored derivative is stale
  const long before_rejected = dp.stats().rejected, before_accepted = dp.stats().accepted;
  double t = t0;
  while (t < t1) {
    local.h = std::min(local.h, t1 - t);
    double taken = 0.0;
    if (!dp.step(sys, t, local.h, y, taken)) throw RunError(step_collapsed_message(local.h, t, o.rtol));
    const double t_new = landed_time(t, taken, t1);
    part.system.after_step(t_new, y);
    dp.invalidate();
    t = t_new;
  }
  local.steps += dp.stats().accepted - before_accepted;
  local.rejected += dp.stats().rejected - before_rejected;
  local.evaluations = dp.stats().evaluations;
}

}  // namespace

RunSummary run_loose(const Model& model, const Decomposition& d, const RunOptions& o, const LooseOptions& lo,
                     ResultSink* sink, LooseStats* stats) {
  check_options(o);
  if (!(lo.macro_step > 0.0) || !std::isfinite(lo.macro_step)) throw InputError("--macro-step: must be a positive time");
  if (lo.extrapolation < 0 || lo.extrapolation > 2) throw InputError("--extrapolation: must be 0, 1 or 2");
  const int threads = lo.threads > 0 ? lo.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  std::vector<Part> parts;
  parts.reserve(d.submodels.size());
  for (const Submodel& s : d.submodels) parts.emplace_back(model, s, 1);
  MultibodySystem whole(model);
  const StateLayout& global = whole.layout();
  History history;
  history.order = lo.extrapolation;
  std::vector<Local> locals(parts.size());
  std::vector<GhostedSystem> systems;
  systems.reserve(parts.size());
  for (std::size_t p = 0; p < parts.size(); ++p) {
    systems.push_back({parts[p], history, global, {}});
    if (o.method == Method::rk4) {
      locals[p].rk4 = std::make_unique<Rk4>(parts[p].system.dimension());
    } else {
      Dopri5Settings s;
      s.rtol = o.rtol;
      s.atol = o.atol;
      locals[p].dopri5 = std::make_unique<Dopri5>(parts[p].system.dimension(), s);
      locals[p].h = o.step;
    }
  }
  RunSummary out;
  LooseStats local_stats;
  LooseStats& st = stats ? *stats : local_stats;
  const auto start = Clock::now();
  Eigen::VectorXd y = whole.initial_state();
  if (sink) sink->begin(whole);
  // One flow-graph node per submodel per macro step, all independent within the step.
  double t0 = 0.0, t1 = 0.0;
  Scheduler schedule(d, 1, 1, [&](std::size_t p, int, int, Half) { integrate(parts[p], locals[p], systems[p], o, t0, t1); });
  const bool adaptive = lo.coupling_tol > 0.0;
  const double dt_out = o.step * o.output_every, order = lo.extrapolation + 1.0;
  std::vector<Eigen::VectorXd> saved(parts.size());
  std::vector<double> saved_h(parts.size());
  Eigen::VectorXd y_new, guess;
  run_with_sink(sink, out, [&] {
    if (sink) emit(whole, sink, o.t_start, y, out);
    // A past for the first macro steps: y(t0 - jH) ~ y0 - jH f(t0, y0). Holding the ghosts
    // at y0 instead would cost one order of the error when bodies start out moving.
    Eigen::VectorXd f0(whole.dimension());
    whole.rhs(o.t_start, y, f0);
    for (int j = lo.extrapolation; j >= 1; --j)
      history.add(o.t_start - j * lo.macro_step, y - (j * lo.macro_step) * f0);
    history.add(o.t_start, y);
    double t = o.t_start, H = lo.macro_step;
    long next_out = 1;
    while (t < o.t_end) {
      // Macro steps land on the output grid (and the end), so snapshots fall on it.
      const double t_out = std::min(o.t_end, o.t_start + static_cast<double>(next_out) * dt_out);
      const bool clipped = t + H >= t_out - 1e-12 * std::max(1.0, std::abs(t_out));
      t0 = t;
      t1 = clipped ? t_out : t + H;
      if (adaptive)
        for (std::size_t p = 0; p < parts.size(); ++p) saved[p] = parts[p].x[0], saved_h[p] = locals[p].h;
      arena.execute([&] { schedule.run(1); });
      if (auto dv = partitioned::check(parts)) throw RunError(divergence_message(model, *dv, t1, o.method, o.step));
      y_new = y;
      partitioned::gather(parts, global, y_new);
      // Coupling error: what each ghost was extrapolated to at t1 against what its owner has.
      const std::vector<double> w = history.weights(t1);
      double dx = 0.0, dv = 0.0;
      guess = y_new;
      for (const Part& part : parts)
        for (int g : part.sub->ghosts) {
          extrapolate_body(history, w, global, g, global, g, guess);
          dx = std::max(dx, (guess.segment<3>(global.position(g)) - y_new.segment<3>(global.position(g))).norm());
          dv = std::max(dv, (guess.segment<3>(global.velocity(g)) - y_new.segment<3>(global.velocity(g))).norm());
        }
      // Step-size factor from the error model e ~ H^(order).
      const double factor = adaptive ? std::clamp(0.9 * std::pow(lo.coupling_tol / std::max(dx, 1e-300), 1.0 / order), 0.2, 2.0) : 1.0;
      if (adaptive && dx > lo.coupling_tol) {  // too far off: back to t0 with a shorter macro step
        for (std::size_t p = 0; p < parts.size(); ++p) parts[p].x[0] = saved[p], locals[p].h = saved_h[p];
        H = (t1 - t0) * factor;
        ++st.rejected;
        if (H < 1e-6 * lo.macro_step) {
          char buf[160];
          std::snprintf(buf, sizeof buf, "coupling error %.3g m above --coupling-tol %.3g m even with a macro step of %.3g s at t = %.6g s",
                        dx, lo.coupling_tol, t1 - t0, t0);
          throw RunError(buf);
        }
        continue;
      }
      y.swap(y_new);
      st.position_error.push_back(dx);
      st.velocity_error.push_back(dv);
      st.max_position_error = std::max(st.max_position_error, dx);
      st.smallest_macro_step = st.macro_steps == 0 ? t1 - t0 : std::min(st.smallest_macro_step, t1 - t0);
      st.largest_macro_step = std::max(st.largest_macro_step, t1 - t0);
      ++st.macro_steps;
      history.add(t1, y);
      if (clipped) {
        if (sink) emit(whole, sink, t1, y, out);
        ++next_out;
      }
      if (adaptive) H = clipped && factor >= 1.0 ? std::max(H, (t1 - t0) * factor) : (t1 - t0) * factor;
      t = t1;
      check_stop(o, t);
      if (o.progress) o.progress(t, st.macro_steps);
    }
  });
  for (const Local& l : locals) {
    out.steps = std::max(out.steps, l.steps);
    out.rejected += l.rejected;
    out.evaluations += l.evaluations;
  }
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  return out;
}

}  // namespace mbsflow
