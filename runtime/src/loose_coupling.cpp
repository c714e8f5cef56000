#include "mbsflow/runtime/loose_coupling.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <limits>
#include <memory>

#include "loose_part.hpp"
#include "loose_advancer.hpp"
#include "loose_rounds.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "sink_runner.hpp"

namespace mbsflow {
namespace {

using loose::LoosePart;
using Clock = std::chrono::steady_clock;

}  // namespace

void check_loose_options(const LooseOptions& lo, std::size_t submodels) {
  if (!(lo.macro_step > 0.0) || !std::isfinite(lo.macro_step)) throw InputError("{macro_step}: must be a positive time");
  if (lo.extrapolation < 0 || lo.extrapolation > 2) throw InputError("{extrapolation}: must be 0, 1 or 2");
  if (lo.max_lag < 0) throw InputError("{max_lag}: must be >= 0");
  if (lo.max_lag > 0 && lo.coupling_tol > 0.0) throw InputError("{max_lag}: needs a fixed macro step (not with {coupling_tol})");
  if (lo.max_lag > 0 && lo.overlap > 0.0) throw InputError("{max_lag}: not with an overlap (set {overlap} to 0)");
  if (!std::isfinite(lo.overlap)) throw InputError("{overlap}: must be a time, 0 (none) or negative (automatic)");
  if (submodels > 0 && !lo.methods.empty() && lo.methods.size() != submodels)
    throw InputError("{methods}: one method per submodel: " + std::to_string(submodels) + " submodels, " +
                     std::to_string(lo.methods.size()) + " methods");
}

double overlap_reach(const LooseOptions& lo) {
  if (lo.max_lag > 0) return 0.0;
  return lo.overlap < 0.0 ? overlap_factor * lo.macro_step : lo.overlap;
}

Decomposition loose_decomposition(const Model& model, const Decomposition& d, const LooseOptions& lo) {
  return with_overlap(model, d, overlap_reach(lo));
}

double cut_joint_stable_step(const Model& model, const Decomposition& d) {
  const std::vector<double> rate = joint_rates(model);
  double fastest = 0.0;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& jt = model.joints[j];
    if (jt.body1 != ground && d.part_of_body[static_cast<std::size_t>(jt.body1)] != d.part_of_body[static_cast<std::size_t>(jt.body2)])
      fastest = std::max(fastest, rate[j]);
  }
  return fastest > 0.0 ? rk4_stability_radius / fastest : std::numeric_limits<double>::infinity();
}

void summarise_records(LooseStats& st) {
  st.position_error.clear();
  st.velocity_error.clear();
  st.lag.clear();
  st.max_position_error = 0.0;
  st.largest_lag = 0;
  st.macro_steps = static_cast<long>(st.records.size());
  for (const CouplingRecord& r : st.records) {
    st.position_error.push_back(r.position_error);
    st.velocity_error.push_back(r.velocity_error);
    st.lag.push_back(r.lag);
    st.max_position_error = std::max(st.max_position_error, r.position_error);
    st.largest_lag = std::max(st.largest_lag, r.lag);
    const double H = r.t_end - r.t_start;
    st.smallest_macro_step = r.index == 1 ? H : std::min(st.smallest_macro_step, H);
    st.largest_macro_step = std::max(st.largest_macro_step, H);
  }
}

namespace {

}  // namespace

RunSummary run_loose(const Model& model, const Decomposition& cut, const RunOptions& o, const LooseOptions& lo,
                     ResultSink* sink, LooseStats* stats) {
  return run_loose(std::make_shared<const Model>(model), cut, o, lo, sink, stats);
}

RunSummary run_loose(std::shared_ptr<const Model> shared, const Decomposition& cut, const RunOptions& o,
                     const LooseOptions& lo, ResultSink* sink, LooseStats* stats) {
  const Model& model = *shared;
  check_options(o);
  check_loose_options(lo, cut.submodels.size());
  const Decomposition d = loose_decomposition(model, cut, lo);
  std::vector<std::unique_ptr<LoosePart>> parts;
  for (std::size_t q = 0; q < d.submodels.size(); ++q)
    parts.push_back(loose::make_part(model, d.submodels[q], o, lo, q));
  MultibodySystem whole(std::move(shared), static_cast<int>(model.bodies.size()));
  const StateLayout& global = whole.layout();
  LooseStats local_stats;
  LooseStats& st = stats ? *stats : local_stats;
  const auto start = Clock::now();
  const bool adaptive = lo.coupling_tol > 0.0;
  loose::MacroGrid grid(o, adaptive ? 0.0 : lo.macro_step);
  loose::LooseRounds rounds(model, d, o, lo, parts, grid, grid.steps_per_run());
  rounds.keep_snapshots = sink != nullptr;
  loose::LooseAdvancer advancer(o, lo, parts, rounds, grid, st, global, whole.initial_state());
  // Checkpoints, at a macro-step end that every submodel has reached and whose snapshots
  // were written (between flow-graph runs): the advancer's part, then the coupling records
  // so far. The numbers depend on the partition, so a resumed run must have the same one
  // (its submodels' states are checked against it).
  loose::CouplingLog log;
  LocalRun::Hooks hooks;
  hooks.restore = [&](StateReader& in) {
    const double t = advancer.restore(in);
    log.restore(in);
    return t;
  };
  hooks.save_state = [&](StateWriter& w) {
    rounds.drain(log);  // records merge by their macro-step end: when does not matter
    log.save(w);
  };
  LocalRun run("loose", o, &whole, sink, std::move(hooks));
  run.begin();
  run.run([&] { return whole.initial_state(); },
          [&] {
            if (!run.resuming()) {
              for (auto& p : parts) p->make_past(o.t_start, lo.macro_step);
              for (int j = 1; j <= lo.extrapolation; ++j) loose::copy_local_ghosts(parts, j);
              for (auto& p : parts) p->start(o.t_start, lo.macro_step);
            }
            drive(advancer, run);
            rounds.catch_up(advancer.at.done);  // the coupling errors of the last macro steps
          },
          [&] {
            rounds.drain(log);
            st.records = log.records();
            summarise_records(st);
            if (sink) sink->write_coupling(st.records);
          });
  RunSummary& out = run.out;
  Eigen::VectorXd y = whole.initial_state();
  for (auto& p : parts) partitioned::gather(p->part, global, y);
  for (const auto& p : parts) {
    out.steps = std::max(out.steps, p->steps);
    out.rejected += p->rejected;
    out.evaluations += p->evaluations;
  }
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  return std::move(out);
}

}  // namespace mbsflow
