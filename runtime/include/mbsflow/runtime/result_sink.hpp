#pragma once
// Where snapshots go. runtime/ knows no file format; io/ implements sinks.
#include <Eigen/Core>
#include <optional>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

struct Snapshot {
  double t = 0.0;
  Eigen::VectorXd state;         // in the layout of system.layout(), quaternions unit
  Eigen::VectorXd joint_wrench;  // 6 per joint (see MultibodySystem::joint_wrenches); empty unless asked for
  std::optional<Energy> energy;  // only if asked for
};

// What a sink wants in each snapshot beyond the state (each costs about one evaluation).
struct SnapshotContent {
  bool joint_wrench = false;
  bool energy = false;
};

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual SnapshotContent content() const { return {}; }
  virtual void begin(const MultibodySystem& system) = 0;
  virtual void write(Snapshot&& snapshot) = 0;
  // Flushes and closes; called on every way out of a run, failed runs included.
  virtual void end() = 0;
};

}  // namespace mbsflow
