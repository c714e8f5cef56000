#pragma once
// What every run loop does with its sink: snapshots with what the sink asked for, and
// closing the sink on every way out so that what was written stays readable.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

// A snapshot of state y at t to the sink, with what the sink asked for. y is moved into
// the snapshot: a run that gathers its state afresh for each snapshot holds no copy of a
// million bodies' state beside the queued ones. A dense output's state (projected: false)
// is projected here unless the sink projects it.
inline void emit(MultibodySystem& sys, ResultSink* sink, double t, Eigen::VectorXd&& y, RunSummary& out,
                 bool projected = true) {
  const SnapshotContent want = sink->content();
  Snapshot s;
  s.t = t;
  s.state = std::move(y);
  if (!projected && !want.projects) sys.after_step(t, s.state);
  s.unprojected = !projected && want.projects;
  if (want.joint_wrench) {
    sys.joint_wrenches(t, s.state, s.joint_wrench);
    s.motor_effort = sys.motor_efforts();
  }
  if (want.energy) s.energy = sys.energy(t, s.state);
  sink->write(std::move(s));
  ++out.snapshots;
  out.t_last_snapshot = t;
}

inline void emit(MultibodySystem& sys, ResultSink* sink, double t, const Eigen::VectorXd& y, RunSummary& out,
                 bool projected = true) {
  sink->make_room();  // before the copy
  emit(sys, sink, t, Eigen::VectorXd(y), out, projected);
}

// "; results keep N snapshots up to t = T s", after what a stop dropped unwritten.
inline std::string results_kept(const ResultSink& sink, const RunSummary& out) {
  char buf[200];
  const SinkLoss loss = sink.loss();
  if (loss.dropped > 0)
    std::snprintf(buf, sizeof buf, "; %ld snapshots not yet written were dropped to stop in time; results keep %ld snapshots up to t = %.6g s",
                  loss.dropped, out.snapshots - loss.dropped, loss.t_last_kept);
  else
    std::snprintf(buf, sizeof buf, "; results keep %ld snapshots up to t = %.6g s", out.snapshots, out.t_last_snapshot);
  return buf;
}

// Runs body(); closes the sink whatever happens; a RunError gets told how far the
// results go.
// before_end() runs first on every way out (a loosely coupled run's coupling records).
template <class F, class G = void (*)()>
void run_with_sink(ResultSink* sink, RunSummary& out, F body, G before_end = [] {}) {
  bool before_end_ran = false;
  auto close_quietly = [sink, &before_end, &before_end_ran] {
    try {
      if (!before_end_ran) before_end();
    } catch (...) {
    }
    try {
      if (sink) sink->end();
    } catch (...) {  // an error on close must not replace the one that ended the run
    }
  };
  try {
    body();
    before_end_ran = true;
    before_end();
  } catch (const RunError& e) {
    close_quietly();
    if (!sink) throw;
    throw RunError(e.text() + results_kept(*sink, out));
  } catch (...) {
    close_quietly();
    throw;
  }
  if (!sink) return;
  sink->end();
  // Stopped while the last snapshots were being written: the run is not complete.
  if (sink->loss().dropped > 0) throw RunError("interrupted while writing the results" + results_kept(*sink, out));
}

// Checkpoints of a run loop (mbsflow/runtime/checkpoint.hpp). A state begins with the
// loop's kind, the method, how far the results go and which results file holds them;
// the loop adds where it is. The sink syncs first, so the file holds every snapshot
// counted.
inline StateWriter checkpoint_head(const char* kind, Method method, ResultSink* sink, const RunSummary& out) {
  if (sink) sink->sync();
  StateWriter w;
  w.text(kind);
  w.text(method.name());
  w.integer(out.snapshots);
  w.real(out.t_last_snapshot);
  w.text(sink ? sink->identity() : "");
  return w;
}

// The reading side: checks the kind and the method, sets out's snapshot count and time,
// and returns the results file's id; `in` is then at the loop's part.
inline std::string read_checkpoint_head(StateReader& in, const char* kind, Method method, RunSummary& out) {
  in.expect(kind);
  const std::string m = in.text();
  if (m != method.name()) in.fail("it is the state of a " + m + " run, not of " + method.name());
  out.snapshots = in.integer(0, INT64_MAX);
  out.t_last_snapshot = in.real();
  return in.text();
}

// After the loop's part: nothing may be left, and the sink goes on with its results.
inline void resume_results(const StateReader& in, const Checkpointing& c, ResultSink* sink, const MultibodySystem& sys,
                           const std::string& results, const RunSummary& out) {
  if (!in.at_end()) in.fail("it holds more than the state of such a run");
  if (!sink) return;
  if (results.empty()) throw InputError(c.resume_from + ": the run it was taken from wrote no results");
  sink->resume(sys, out.snapshots, results);
}

// The output grid in s of model time (see RunOptions).
inline double output_dt(const RunOptions& o) {
  return o.output_interval > 0.0 ? o.output_interval : o.step * o.output_every;
}

// Adaptive methods: the snapshots between two steps come from the dense output on the
// uniform grid t_start + k output_dt(o), k = next, next + 1, ... up to t_new and short of
// t_end (where the last step's end is the snapshot). Calls at(k, t_out) for each; returns
// the index of the next grid time. Every run loop of an adaptive method goes through it.
template <class F>
long dense_outputs(const RunOptions& o, long next, double t_new, F at) {
  const double dt = output_dt(o);
  for (;; ++next) {
    const double t_out = o.t_start + static_cast<double>(next) * dt;
    if (t_out > t_new || t_out >= o.t_end) return next;
    at(next, t_out);
  }
}

// Fixed-step methods: the steps between snapshots.
inline int output_steps(const RunOptions& o) {
  if (!(o.output_interval > 0.0)) return o.output_every;
  return static_cast<int>(std::llround(o.output_interval / o.step));
}

// The checks every run loop makes of its options before it starts, and a worker of the
// options a coordinator sends: one validation of each setting, wherever it comes from.
inline void check_options(const RunOptions& o) {
  if (!std::isfinite(o.t_start) || !std::isfinite(o.t_end)) throw InputError("t_start and t_end must be finite");
  if (!(o.t_end > o.t_start)) throw InputError("t_end must be greater than t_start");
  if (!(o.step > 0.0) || !std::isfinite(o.step)) throw InputError("the step must be a positive finite number");
  if (o.output_every < 1) throw InputError("output_every must be >= 1");
  // Tolerances: those of an adaptive method positive, any finite and not negative.
  if (!(o.rtol >= 0.0) || !std::isfinite(o.rtol) || !(o.atol >= 0.0) || !std::isfinite(o.atol) ||
      (stepper_entry(o.method).adaptive && !o.fixed_step && (o.rtol == 0.0 || o.atol == 0.0)))
    throw InputError("rtol and atol must be positive finite numbers");
  if (o.linear_solver != "auto" && o.linear_solver != "dense" && o.linear_solver != "banded" && o.linear_solver != "klu" &&
      o.linear_solver != "sparselu")
    throw InputError("unknown linear solver '" + o.linear_solver + "' (auto, dense, banded, klu or sparselu)");
  if (o.jacobian != "auto" && o.jacobian != "differences")
    throw InputError("the Jacobian must be auto (analytic where the model has one) or differences, not '" + o.jacobian + "'");
  if (o.fixed_step && !stepper_entry(o.method).implicit)
    throw InputError("a fixed step without error control is for " +
                     method_names([](const StepperEntry& e) { return e.implicit; }, "and") + ", not " + o.method.name());
  if (o.output_interval < 0.0 || !std::isfinite(o.output_interval))
    throw InputError("the output interval must be a positive finite number");
  if (o.output_interval > 0.0 && !stepper_entry(o.method).adaptive) {
    const double k = std::round(o.output_interval / o.step);
    if (k < 1.0 || k > 1e9 || std::abs(k * o.step - o.output_interval) > 1e-9 * o.output_interval) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "the output interval %.6g s is not a whole number of %s steps of %.6g s",
                    o.output_interval, o.method.name(), o.step);
      throw InputError(buf);
    }
  }
}

inline StepperSettings stepper_settings(const RunOptions& o) {
  StepperSettings s;
  const bool implicit = stepper_entry(o.method).implicit;
  s.step = implicit && !o.step_given && !o.fixed_step ? 0.0 : o.step;  // 0: the method's own first step
  s.rtol = o.rtol;
  s.atol = o.atol;
  s.threads = o.threads;
  s.variant = o.variant;
  s.linear_solver = o.linear_solver;
  s.fixed_step = o.fixed_step;
  return s;
}

// RunError if the state y at t has diverged (naming the body and a step that works).
inline void check_diverged(const MultibodySystem& sys, const Eigen::VectorXd& y, double t, const RunOptions& o) {
  if (auto d = find_divergence(sys.layout(), y)) throw RunError(divergence_message(sys.model(), *d, t, o.method, o.step));
}

inline void check_stop(const RunOptions& o, double t) {
  if (o.stop && o.stop->load(std::memory_order_relaxed)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "interrupted at t = %.6g s", t);
    throw RunError(buf);
  }
}

}  // namespace mbsflow
