#pragma once
// Runs a multibody system from t_start to t_end with RK4 or DOPRI5 and hands
// snapshots to a sink. Throws RunError if the state diverges or the step collapses.
#include <atomic>
#include <functional>

#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow {

struct RunOptions {
  Method method = Method::rk4;
  double t_start = 0.0;
  double t_end = 1.0;
  double step = 1e-3;    // RK4: the step; DOPRI5: first step and output grid unit
  int output_every = 1;  // snapshot every k steps (RK4) or every k*step of time (DOPRI5)
  double rtol = 1e-6, atol = 1e-8;
  // Called now and then with the time reached and the steps taken; may be empty.
  std::function<void(double t, long steps)> progress;
  // When set and it becomes true (a signal handler may set it), the run stops after the
  // current step with a RunError; what was written stays written.
  const std::atomic<bool>* stop = nullptr;
};

struct RunSummary {
  long steps = 0;
  long rejected = 0;
  long evaluations = 0;
  long snapshots = 0;
  double t_last_snapshot = 0.0;
  double wall_seconds = 0.0;
  Eigen::VectorXd final_state;
};

// Options from the model's simulation block; step from the stable-step estimate if unset.
RunOptions options_from_model(const Model& model);

RunSummary run_simulation(MultibodySystem& system, const RunOptions& options, ResultSink* sink);

}  // namespace mbsflow
