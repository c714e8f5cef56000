#pragma once
// Where snapshots go. runtime/ knows no file format; io/ implements sinks.
#include <Eigen/Core>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual void begin(const MultibodySystem& system) = 0;
  // y: the full state in the layout of system.layout(), quaternions unit.
  virtual void write(double t, const Eigen::VectorXd& y) = 0;
  virtual void end() = 0;
};

}  // namespace mbsflow
