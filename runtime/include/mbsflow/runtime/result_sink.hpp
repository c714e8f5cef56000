#pragma once
// Where snapshots go. runtime/ knows no file format; io/ implements sinks.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

struct Snapshot {
  double t = 0.0;
  Eigen::VectorXd state;         // in the layout of system.layout(), quaternions unit
  Eigen::VectorXd joint_wrench;  // 6 per joint (see MultibodySystem::joint_wrenches); empty unless asked for
  Eigen::VectorXd motor_effort;  // 1 per joint (MultibodySystem::motor_efforts), with joint_wrench
  std::optional<Energy> energy;  // only if asked for
  // A dense output's state, not yet made consistent (MultibodySystem::after_step): only
  // for a sink whose content() says it projects.
  bool unprojected = false;
};

// What a sink wants in each snapshot beyond the state (each costs about one evaluation).
struct SnapshotContent {
  bool joint_wrench = false;
  bool energy = false;
  // The sink projects a dense output's state itself (AsyncSink: on its writer thread, off
  // the run's), so the run hands it over unprojected.
  bool projects = false;
};

// One macro step of a loosely coupled run (loose_coupling.hpp), over all submodels: the
// coupling error at its end (how far the neighbours' extrapolated boundary bodies were
// from what they then sent) and how old the newest neighbour values were that a submodel
// stepped from (macro steps; 0 in a synchronous run).
struct CouplingRecord {
  long index = 0;  // macro-step end 1, 2, ...
  double t_start = 0.0, t_end = 0.0;
  double position_error = 0.0, velocity_error = 0.0;  // m, m/s
  int lag = 0;
};

// What a stopped run did not write: snapshots handed to write() but dropped so that the
// run ends in time (AsyncSink), and the time of the last one kept.
struct SinkLoss {
  long dropped = 0;
  double t_last_kept = 0.0;
};

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual SnapshotContent content() const { return {}; }
  virtual void begin(const MultibodySystem& system) = 0;
  virtual void write(Snapshot&& snapshot) = 0;
  // Returns once write() would take a snapshot without waiting (AsyncSink: the writer has
  // room), so that a run gathers the state it will hand over only then; a million bodies'
  // state is 104 MB.
  virtual void make_room() {}
  // Loosely coupled runs: the macro steps' records, once, before end() (failed runs too).
  virtual void write_coupling(const std::vector<CouplingRecord>& records) { (void)records; }
  // Flushes and closes; called on every way out of a run, failed runs included.
  virtual void end() = 0;
  virtual SinkLoss loss() const { return {}; }  // after end()

  // Checkpoints. sync(): returns once every snapshot written so far is stored (a file
  // flushed to disk). identity(): after begin(), what tells these results from any other
  // run's (a results file's random id); a checkpoint keeps it.
  virtual void sync() {}
  virtual std::string identity() const { return {}; }
  // Instead of begin(): goes on with the results of an earlier run of this system that
  // a checkpoint was taken from (identity() was `identity` then), keeping its first
  // `snapshots` snapshots and dropping any later ones. InputError when the results are
  // not there or not those.
  virtual void resume(const MultibodySystem& system, long snapshots, const std::string& identity) {
    (void)system, (void)snapshots, (void)identity;
    throw InputError("this output cannot go on from a checkpoint");
  }
};

}  // namespace mbsflow
