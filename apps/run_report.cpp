#include "run_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "huge_pages.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/words.hpp"
#include "phase_timings.hpp"

namespace mbsflow::cli {
namespace {

// How many bodies the submodels of a loose run borrow, all together.
std::size_t borrowed_bodies(const Model& m, const Decomposition& d, const LooseOptions& lo) {
  std::size_t n = 0;
  for (const Submodel& s : loose_decomposition(m, d, lo).submodels) n += s.borrowed.size();
  return n;
}

std::string human_bytes(double b) {
  const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024.0 && u < 4) {
    b /= 1024.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g %s", b, unit[u]);
  return buf;
}

}  // namespace

void say_options(const Model& m, const RunRequest& a, const StableStep& s, const RunOptions& o) {
  const char* name = method_name(o.method);
  if (m.simulation.step) {
    if (!stepper_entry(o.method).adaptive && *m.simulation.step > s.step)
      std::fprintf(stderr, "mbsflow: warning: step %.3g s is above the estimated RK4 stability limit %s\n",
                   *m.simulation.step, s.describe(m).c_str());
    return;
  }
  if (a.quiet) return;
  char tolerances[64];
  std::snprintf(tolerances, sizeof tolerances, "rtol %.3g, atol %.3g", o.rtol, o.atol);
  if (o.method_chosen && !m.beams.empty()) {
    std::fprintf(stderr, "mbsflow: beams are stiff: %s, adaptive, %s (--method, --step, --rtol and --atol choose)\n", name,
                 tolerances);
  } else if (o.method_chosen && o.method != Method::rk4) {
    std::fprintf(stderr,
                 "mbsflow: no joint gives RK4 a stable step (no compliant joint): %s, adaptive, %s (--method, --step, "
                 "--rtol and --atol choose)\n", name, tolerances);
  } else if (stepper_entry(o.method).implicit) {
    std::fprintf(stderr, "mbsflow: no step given: %s picks its first step from the tolerances (%s)\n", name, tolerances);
  } else if (stepper_entry(o.method).adaptive) {
    std::fprintf(stderr, "mbsflow: no step given: %s starts with %.4g s (%s) and adapts it to %s\n", name, o.step,
                 std::isfinite(s.step) ? "the RK4 stability estimate" : "a thousandth of the run", tolerances);
  } else {
    char fit[96] = "", every[64] = "";
    if (o.step != s.step) std::snprintf(fit, sizeof fit, ", shortened to %.4g s to fit the output interval", o.step);
    if (!m.simulation.output_every && o.output_interval <= 0.0 && o.output_every > 1)
      std::snprintf(every, sizeof every, "; a snapshot every %d steps", o.output_every);
    std::fprintf(stderr, "mbsflow: no step given: RK4 with the stability estimate %s%s%s\n", s.describe(m).c_str(), fit,
                 every);
  }
}

// The lines that say how the run was cut and where its submodels run (cluster: the worker
// processes', null on threads), and an implicit method's Jacobian.
void say_cut(const Model& m, const RunRequest& a, const RunOptions& o, const std::optional<Decomposition>& d,
             const ClusterConfig* cluster_config, const std::optional<LooseOptions>& loose_options, int threads) {
  const bool cluster = cluster_config != nullptr;
  const bool loose = loose_options.has_value();
  const LooseOptions lo = loose_options.value_or(LooseOptions{});
  const double macro_step = lo.macro_step;
  if (cluster && !a.quiet) {
    char coupling[96] = "";
    if (loose) std::snprintf(coupling, sizeof coupling, ", loosely coupled: macro step %.4g s", macro_step);
    std::fprintf(stderr, "mbsflow: %zu submodels on %zu worker processes (%s), %d cut joints, load imbalance %.1f %%%s\n",
                 d->submodels.size(), cluster_config->workers.size(), cluster_config->transport.c_str(), d->cut_joints, 100.0 * d->imbalance, coupling);
  }
  else if (loose && !a.quiet && d->submodels.size() == 1)
    std::fprintf(stderr, "mbsflow: 1 submodel: nothing to couple loosely, a plain run (--partitions N cuts the model "
                         "into N submodels)\n");
  else if (loose && !a.quiet)
    std::fprintf(stderr,
                 "mbsflow: %zu submodels on %d threads, loosely coupled: macro step %.4g s (%.3g x the cut joints' "
                 "RK4 stable step), extrapolation order %d, overlap %.4g s (%zu bodies borrowed)%s\n",
                 d->submodels.size(), threads, macro_step, macro_step / cut_joint_stable_step(m, *d), a.extrapolation,
                 overlap_reach(lo), borrowed_bodies(m, *d, lo), lo.coupling_tol > 0.0 ? ", error control" : "");
  else if (d && !a.quiet)
    std::fprintf(stderr, "mbsflow: %zu submodels on %d threads (%s), %d cut joints, load imbalance %.1f %%\n",
                 d->submodels.size(), threads, a.executor == "flow" ? "flow graph" : "barrier per stage", d->cut_joints,
                 100.0 * d->imbalance);
  if (stepper_entry(o.method).implicit && !loose && !cluster && !a.quiet) {  // an implicit method on the whole model
    std::string why;
    if (o.jacobian == "differences")
      std::fprintf(stderr, "mbsflow: Jacobian by coloured differences (--jacobian differences)\n");
    else if (has_analytic_jacobian(m, &why))
      std::fprintf(stderr, "mbsflow: analytic Jacobian\n");
    else
      std::fprintf(stderr, "mbsflow: Jacobian by coloured differences: no analytic one for %s\n", why.c_str());
  }
}

void print_coupling(const LooseStats& ls, bool adaptive, int max_lag, double tol, bool cluster) {
  char adapt[128] = "", lag[96] = "";
  if (adaptive && ls.over_tolerance > 0)
    std::fprintf(stderr,
                 "mbsflow: warning: %ld macro steps kept a coupling error above --coupling-tol %.3g m at the smallest "
                 "macro step (1/1024 of --macro-step); a larger --overlap may help\n",
                 ls.over_tolerance, tol);
  if (!adaptive && tol > 0.0 && ls.max_position_error > tol)
    std::fprintf(stderr,
                 "mbsflow: warning: the coupling error %.3g m is above %.3g m with a fixed macro step: give a "
                 "smaller --macro-step, a larger --overlap or --coupling-tol\n",
                 ls.max_position_error, tol);
  if (adaptive && cluster)  // the workers do not report how many they took again
    std::snprintf(adapt, sizeof adapt, "; macro step %.3g .. %.3g s", ls.smallest_macro_step, ls.largest_macro_step);
  else if (adaptive)
    std::snprintf(adapt, sizeof adapt, "; macro step %.3g .. %.3g s, %ld taken again", ls.smallest_macro_step,
                  ls.largest_macro_step, ls.rejected);
  if (max_lag > 0) {
    long lagged = 0;
    for (int l : ls.lag) lagged += l > 0 ? 1 : 0;
    std::snprintf(lag, sizeof lag, "; %ld macro steps from older values, at most %d steps old", lagged, ls.largest_lag);
  }
  std::fprintf(stderr, "mbsflow: coupling error over %ld macro steps: ghost positions off by at most %.3g m, last %.3g m%s%s\n",
               ls.macro_steps, ls.max_position_error, ls.position_error.empty() ? 0.0 : ls.position_error.back(), adapt, lag);
}

void print_summary(const Model& m, MultibodySystem& sys, const RunOptions& o, const RunSummary& r) {
  const Energy e0 = sys.energy(o.t_start, sys.initial_state());
  const Energy e1 = sys.energy(o.t_end, r.final_state);
  const StateLayout& l = sys.layout();
  std::printf("model %s: %s, %s; %s, step %.4g s, t = %g..%g s\n", m.name.c_str(),
              count_of(static_cast<long long>(m.bodies.size()), "body", "bodies").c_str(),
              count_of(static_cast<long long>(m.joints.size()), "joint").c_str(), method_name(o.method), o.step, o.t_start, o.t_end);
  std::printf("energy (kinetic + gravity + elastic): initial %.10g J, final %.10g J\n", e0.total(), e1.total());
  const std::size_t shown = std::min<std::size_t>(m.bodies.size(), 10);
  std::printf("final state of %s%s:\n", shown < m.bodies.size() ? "the first " : "",
              shown == 1 ? "the body" : count_of(static_cast<long long>(shown), "body", "bodies").c_str());
  std::printf("  %-16s %14s %14s %14s %14s %14s %14s\n", "body", "x", "y", "z", "vx", "vy", "vz");
  for (std::size_t i = 0; i < shown; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const auto& y = r.final_state;
    std::printf("  %-16s %14.6g %14.6g %14.6g %14.6g %14.6g %14.6g\n", m.bodies[i].name.c_str(), y[l.position(k)],
                y[l.position(k) + 1], y[l.position(k) + 2], y[l.velocity(k)], y[l.velocity(k) + 1], y[l.velocity(k) + 2]);
  }
}

void say_done(const Model& m, const RunSummary& r, const AsyncSink* sink, const std::string& output_path, long checkpoints,
              const std::string& checkpoint_at) {
  const double body_steps = static_cast<double>(r.steps) * static_cast<double>(m.bodies.size());
  std::string output;
  if (sink) {
    const double bytes = static_cast<double>(std::filesystem::file_size(output_path));
    output = ", " + std::to_string(r.snapshots) + " snapshots, " + human_bytes(bytes) + " in " + output_path;
    if (sink->stats().waits > 0)
      output += " (the writer held the run back " + std::to_string(sink->stats().waits) + " times)";
  }
  const std::string newton = r.jacobians > 0 ? " (" + std::to_string(r.jacobians) + " Jacobians, " +
                                                   std::to_string(r.factorizations) + " factorisations)"
                                             : "";
  if (r.resumed_at) {
    char from[96];
    std::snprintf(from, sizeof from, "; went on from the checkpoint at t = %.6g s", *r.resumed_at);
    output += from;
  }
  if (checkpoints > 0) output += "; " + std::to_string(checkpoints) + " checkpoints, the last in " + checkpoint_at;
  // The process's peak resident memory: model, systems, workspace and output buffers (on
  // worker processes, theirs are their own).
  if (const double peak = memory_use().peak_bytes; peak > 0.0) {
    char mem[96];
    // Per body only where the bodies, not the program, take most of it.
    if (m.bodies.size() >= 1000)
      std::snprintf(mem, sizeof mem, "; peak memory %s (%.0f B per body)", human_bytes(peak).c_str(),
                    peak / static_cast<double>(m.bodies.size()));
    else
      std::snprintf(mem, sizeof mem, "; peak memory %s", human_bytes(peak).c_str());
    output += mem;
  }
  std::fprintf(stderr, "mbsflow: done: %ld steps (%ld rejected), %ld evaluations%s, %.3f s wall, %.3g body-steps/s%s\n",
               r.steps, r.rejected, r.evaluations, newton.c_str(), r.wall_seconds,
               body_steps / std::max(r.wall_seconds, 1e-9), output.c_str());
}

}  // namespace mbsflow::cli
