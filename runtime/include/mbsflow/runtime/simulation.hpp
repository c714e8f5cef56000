#pragma once
// Runs a multibody system from t_start to t_end with any registered method and hands
// snapshots to a sink. Throws RunError if the state diverges or the step collapses.
#include <atomic>
#include <functional>
#include <string>

#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <vector>

#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/checkpoint.hpp"
#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow {

// What a phase of a run was: part of its set-up, or the steps (with the results written).
enum class RunPhase { set_up, steps };

struct RunOptions {
  Method method = Method::rk4;  // any method of the stepper registry (mbsflow/methods/stepper.hpp)
  bool method_chosen = false;   // the model named none: options_from_model chose it
  std::string variant;           // its variant (colloc: "m,s[,order]", tirk: tableau and/or iteration); empty: default
  std::string linear_solver = "auto";  // implicit methods' Newton matrices: auto, dense, banded, klu, sparselu
  // Implicit methods' Jacobian: "auto" (analytic where every force element has one, see
  // MultibodySystem::has_analytic_jacobian; else differences by colour) or "differences".
  std::string jacobian = "auto";
  double t_start = 0.0;
  double t_end = 1.0;
  double step = 1e-3;    // fixed-step methods (RK4): the step; adaptive ones: the first step
  // False when `step` is only the RK4 stability estimate (the model gives none): the
  // implicit methods then pick their first step from the tolerances (Hairer & Wanner's
  // starting step), since the explicit stability limit says nothing about theirs.
  bool step_given = true;
  bool fixed_step = false;  // colloc, tirk: keep `step` throughout, without error control (order studies)
  // The output grid: a snapshot every output_interval s of model time when it is > 0 (for
  // fixed-step methods a whole number of steps), else every output_every steps (fixed-step
  // methods) or every output_every * step s (adaptive ones); and one at the end.
  int output_every = 1;
  double output_interval = 0.0;
  double rtol = 1e-6, atol = 1e-8;
  // Threads of an implicit method on a whole model (its stages, slices and Jacobian
  // columns); 0: all cores. The numbers do not depend on it.
  int threads = 0;
  // Called now and then with the time reached and the steps taken; may be empty.
  std::function<void(double t, long steps)> progress;
  // When set and it becomes true (a signal handler may set it), the run stops after the
  // current step with a RunError; what was written stays written.
  const std::atomic<bool>* stop = nullptr;
  // Checkpoints to write, or one to go on from (mbsflow/runtime/checkpoint.hpp); may be null.
  Checkpointing* checkpoint = nullptr;
  // Told as each part of a run's set-up ends ("build the system", "start the results
  // file", ...) and when the steps end, so that mbsflow run --timings can say what each
  // took and held; may be empty.
  std::function<void(const char* phase, RunPhase kind)> phase;
};

// Calls o.phase(name, kind) if it is set.
inline void phase_done(const RunOptions& o, const char* name, RunPhase kind = RunPhase::set_up) {
  if (o.phase) o.phase(name, kind);
}

struct RunSummary {
  long steps = 0;
  long rejected = 0;
  long evaluations = 0;
  long jacobians = 0, factorizations = 0;  // implicit methods on a whole model
  long snapshots = 0;
  double t_last_snapshot = 0.0;
  std::optional<double> resumed_at;  // a run that went on from a checkpoint: the checkpoint's time
  double wall_seconds = 0.0;
  Eigen::VectorXd final_state;
};

// Options from the model's simulation block. Without a step, the stable-step estimate
// (shortened for fixed-step methods so that the output interval is a whole number of
// steps). Adaptive methods with neither a step nor an output interval write 1000
// snapshots per output_every over the run, so the output does not follow the estimate.
// stable_step: estimate_stable_step(model).step when the caller has it already.
RunOptions options_from_model(const Model& model, std::optional<double> stable_step = std::nullopt);

RunSummary run_simulation(MultibodySystem& system, const RunOptions& options, ResultSink* sink);

// One body's state, world frame (angular velocity too).
struct BodyState {
  Eigen::Vector3d position, velocity, angular_velocity;
  Eigen::Quaterniond orientation;  // body to world
};

// A model stepped by the embedding program, with any registered method: read states and
// set loads between steps (a controller in the loop). The numbers are those of
// run_simulation with the same options (until a load or an input changes).
class Simulation {
 public:
  explicit Simulation(const Model& model);  // options from the model's simulation block
  Simulation(const Model& model, const RunOptions& options);
  ~Simulation();

  // A user force element (force_element.hpp). An element whose inputs the program changes
  // between steps: call inputs_changed() after changing them.
  void add_force_element(std::shared_ptr<const ForceElement> element);
  // A force and torque (world frame, at the centre of mass) on a body, held until set
  // again; replaces what was set before for that body.
  void set_load(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque = Eigen::Vector3d::Zero());
  // The method starts anew from the current state (what it kept of f is stale).
  void inputs_changed() { restart_ = true; }
  // When set and it becomes true (a signal handler may set it), step() and advance_to()
  // throw RunError before their next step; the state stays that of the last step.
  void set_stop(const std::atomic<bool>* stop) { o_.stop = stop; }

  // One step of the method towards the options' t_end; false (and nothing done) once there.
  bool step();
  // Steps until time t exactly (the last step shortened), t_end or not.
  void advance_to(double t);

  double time() const;
  const Eigen::VectorXd& state() const;  // in system().layout()
  BodyState body(int index) const;
  // Sets the whole state between steps (quaternions renormalised, prescribed motion imposed).
  void set_state(const Eigen::VectorXd& y);
  const StepperStats& stats() const;
  MultibodySystem& system() { return *system_; }
  const RunOptions& options() const { return o_; }

 private:
  struct HeldLoad;
  void ready(double t_end);
  void take_step();  // one step, then the divergence check

  std::unique_ptr<MultibodySystem> system_;  // not moved: the stepper's system refers to it
  RunOptions o_;
  StepperSystem stepper_system_;
  std::unique_ptr<Stepper> stepper_;
  std::vector<std::shared_ptr<HeldLoad>> loads_;  // per body, made on the first set_load
  bool restart_ = false;
};

}  // namespace mbsflow
