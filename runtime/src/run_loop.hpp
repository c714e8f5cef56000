#pragma once
// The loop of every run, written once. An Advancer takes the run forward by one step, one
// chunk of the tight flow graph's stages or one round of macro steps, and tells a
// RunObserver what happened: each step's end and the snapshots that fell due. Between two
// advances the loop asks the observer whether a checkpoint is due and has the advancer
// write its part of it. What the observer does with it is where runs differ: in one
// process, LocalRun (the guards, the snapshots to the sink, progress, checkpoints with
// their head, the results closed on every way out); in a worker, reports to the
// coordinator, which does the same for all of them.
#include <functional>
#include <string>

#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/runtime/checkpoint.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

class RunObserver {
 public:
  virtual ~RunObserver() = default;
  // After `steps` steps, at t: throws to stop the run (diverged, interrupted, stopped
  // elsewhere); reports progress, and with snapshot >= 0 the state at t as snapshot
  // number `snapshot`.
  virtual void step_done(long steps, double t, long snapshot) = 0;
  // An advance of macro steps reached t, before its snapshots: throws to stop there (a
  // worker told to stop).
  virtual void reached(double t) { (void)t; }
  // A snapshot between two steps, number `index` at t: the advancer's entries of y (the
  // whole model's layout) are set; projected: already on the joints and drivers (a loose
  // submodel's kept snapshot), else dense output, which the observer projects.
  virtual void dense(long index, double t, Eigen::VectorXd& y, bool projected = false) = 0;
  // False: nothing takes snapshots between steps (no dense output to compute).
  virtual bool wants_dense() const { return true; }
  // Asked between two advances: whether a checkpoint is due now; then checkpoint() takes
  // it, save() writing the advancer's part.
  virtual bool checkpoint_due() { return false; }
  virtual void checkpoint(const std::function<void(StateWriter&)>& save) { (void)save; }
};

class Advancer {
 public:
  virtual ~Advancer() = default;
  virtual bool done() const = 0;
  // One step, chunk or round, told to `to` as it goes.
  virtual void advance(RunObserver& to) = 0;
  // Where it is, for a checkpoint between two advances.
  virtual void save(StateWriter& w) = 0;
};

// Advances until done, with a checkpoint wherever the observer wants one.
void drive(Advancer& a, RunObserver& to);

// A run in this process: the results go to a sink (may be null) of the whole model's
// system, checkpoints to o.checkpoint. The advancer's checks and state come through
// hooks, since a whole model's stepper and a partitioned run's parts hold them apart.
class LocalRun final : public RunObserver {
 public:
  struct Hooks {
    std::function<void(double t)> check;                 // RunError if the state at t diverged; may be empty
    std::function<void(Eigen::VectorXd& y)> state;       // the state at the last step's end
    std::function<double(StateReader& in)> restore;      // the advancer's part of a checkpoint; returns its time
    std::function<void(StateWriter& w)> save_state;      // after the advancer's part (a partitioned run's state); may be empty
    long progress_every = 1;                             // steps between progress reports
  };
  // kind: the checkpoint's ("simulation", "tight", "loose"); whole: null where there is
  // neither a sink nor checkpoints.
  LocalRun(const char* kind, const RunOptions& o, MultibodySystem* whole, ResultSink* sink, Hooks hooks);

  RunSummary out;
  bool resuming() const { return o_.checkpoint && !o_.checkpoint->resume.empty(); }
  // A fresh run's results file begun, or the checkpoint read back (head, the advancer's
  // part, the results file taken up).
  void begin();
  // The first snapshot (a fresh run's, of first()), then body(), the results closed
  // whatever happens (before_end() first, on every way out).
  void run(const std::function<Eigen::VectorXd()>& first, const std::function<void()>& body,
           const std::function<void()>& before_end = [] {});

  void step_done(long steps, double t, long snapshot) override;
  void dense(long index, double t, Eigen::VectorXd& y, bool projected) override;
  bool wants_dense() const override { return sink_ != nullptr; }
  bool checkpoint_due() override { return timer_.due(); }
  void checkpoint(const std::function<void(StateWriter&)>& save) override;

 private:
  const char* kind_;
  const RunOptions& o_;
  MultibodySystem* whole_;
  ResultSink* sink_;
  Hooks hooks_;
  CheckpointTimer timer_;
  Eigen::VectorXd y_;  // the state gathered for a snapshot (moved into it)
};

}  // namespace mbsflow
