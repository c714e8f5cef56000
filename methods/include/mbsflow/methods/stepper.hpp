#pragma once
// One interface for advancing a system by one step, whatever the method: the explicit
// Runge-Kutta methods, the collocation block methods and the triangularised implicit
// Runge-Kutta methods all come behind it. A stepper owns its state, reports what it did
// and gives dense output inside its last step. Every run mode drives steppers: a whole
// model, a loosely coupled submodel (a macro step is steps of a stepper between
// exchanges) or a plain ODE.
//
// Adding a method is one file that implements Stepper and one line in the registry
// (methods/src/stepper_registry.cpp); the model format, the CLI (--method NAME) and the
// embedding API then know it by its name.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "mbsflow/error.hpp"
#include "mbsflow/method.hpp"
#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/state_archive.hpp"

namespace mbsflow {

// What a stepper integrates: y' = f(t, y). Every stepper calls rhs from one thread at a
// time, so it may work in scratch of its own.
struct StepperSystem {
  Eigen::Index size = 0;
  using Rhs = std::function<void(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt)>;
  Rhs rhs;
  // Optional: makes another rhs, giving the same numbers, that works in scratch of its
  // own, so that calls of the ones it made may overlap each other (not rhs or jacobian,
  // with which calls of another_rhs itself do not overlap). The implicit methods then
  // evaluate their stages and difference columns on several threads at once; without it
  // those calls take turns.
  std::function<Rhs()> another_rhs;
  // Optional: after every accepted step, puts the state back on its manifold (a multibody
  // model renormalises quaternions and imposes prescribed motion).
  std::function<void(double t, Eigen::VectorXd& y)> after_step;
  // Optional: the Jacobian df/dy in a matrix of pattern `sparsity` (implicit methods;
  // without it they take finite differences, grouped by the pattern's column colouring).
  std::function<void(double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac)> jacobian;
  // Optional: makes that pattern. Called only by the methods that use a Jacobian, once
  // each, so the explicit methods never pay for building it.
  std::function<Eigen::SparseMatrix<double>()> sparsity;
  // Optional: blocks of unknowns the implicit methods' sparse solvers may eliminate first
  // (OdeProblem::eliminable).
  std::vector<RowRange> eliminable;
  // Optional: what unknown i is, for the message of a failed run.
  std::function<std::string(Eigen::Index i)> describe;
};

struct StepperSettings {
  double step = 0.0;  // fixed-step methods: the step; adaptive ones: the first step (0: their own choice)
  double rtol = 1e-6, atol = 1e-8;
  Eigen::VectorXd rtols, atols;  // implicit methods: per-component tolerances (empty: rtol, atol)
  int threads = 1;      // threads inside one step (the implicit methods' stage nodes); 0: all cores
  std::string variant;  // method-specific: tirk's tableau, colloc's "m,s[,order]"; empty: the default
  std::string linear_solver = "auto";  // implicit methods: auto, dense, banded, klu or sparselu
  bool fixed_step = false;  // colloc, tirk: every step is `step`, no error control (order studies)
};

struct StepperStats {
  long accepted = 0, rejected = 0, evaluations = 0;
  long jacobians = 0, factorizations = 0;  // implicit methods (evaluations include the Jacobians' differences)
};

class Stepper {
 public:
  virtual ~Stepper() = default;
  // (Re)starts at (t, y); no step goes past t_end. Called again whenever the state or the
  // system's inputs changed between steps (a controller, the next macro step of loose
  // coupling): an adaptive method keeps the step size it had reached.
  virtual void start(double t, const Eigen::VectorXd& y, double t_end) = 0;
  // One accepted step (rejected attempts happen inside). RunError when the step size
  // collapses or an implicit iteration cannot be made to converge.
  virtual void step() = 0;
  // Dense output anywhere in the last accepted step [t_previous(), t()], before the
  // after_step projection.
  virtual void dense(double t, Eigen::VectorXd& out) const = 0;
  // Adaptive methods: the step size the next step starts from, kept and put back to take
  // a stretch again (loose coupling's rollback).
  virtual double next_step() const { return 0.0; }
  virtual void set_next_step(double /*h*/) {}

  double t() const { return t_; }
  double t_previous() const { return t_previous_; }
  double t_end() const { return t_end_; }
  bool done() const { return t_ >= t_end_; }
  const Eigen::VectorXd& y() const { return y_; }
  // Sets the state between steps (the next step starts from it; adaptive methods forget
  // what they kept of f).
  void set_state(const Eigen::VectorXd& y) { start(t_, y, t_end_); }
  const StepperStats& stats() const { return stats_; }

  // Checkpoints, between steps: everything the next steps depend on (the state, the step
  // size controller, kept f values, the Newton matrices' history), so that a stepper made
  // with the same system and settings and restored goes on bit for bit as this one would
  // have. restore() follows a start() (which sizes the state) and throws InputError for a
  // state of another method or size.
  void save(StateWriter& out) const;
  void restore(StateReader& in);

 protected:
  virtual void save_method(StateWriter& out) const = 0;
  virtual void restore_method(StateReader& in) = 0;

  double t_ = 0.0, t_previous_ = 0.0, t_end_ = 0.0;
  Eigen::VectorXd y_;
  mutable StepperStats stats_;  // mutable: dense output may evaluate f (rk4 does, for its slopes)
};

// The registry: one entry per method, with what it can do. Every decision a run makes
// about a method (how it takes its first step, which tolerances it accepts, whether its
// stages can be spread over submodels) reads these, never the method's name.
using StepperFactory = std::unique_ptr<Stepper> (*)(const StepperSystem& system, const StepperSettings& settings);
struct StepperEntry {
  Method method;
  const char* summary;
  // false: fixed steps of StepperSettings::step (snapshots every k steps; a step above the
  // stability limit diverges, and a smaller step is the advice).
  bool adaptive;
  // Solves for its stages with the Jacobian: picks its first step from the tolerances,
  // takes per-component tolerances, a linear solver and StepperSettings::fixed_step.
  bool implicit;
  // The stages a tightly coupled run of several submodels exchanges, one after another
  // (the stage schemes of runtime/src/partitioned_state.hpp); 0: the method integrates a
  // whole model (its stages run in parallel inside the step) or a loosely coupled submodel.
  int tight_stages;
  StepperFactory make;
};
// Whether a tightly coupled run of several submodels can exchange the method's stages.
inline bool has_stage_scheme(const StepperEntry& e) { return e.tight_stages > 0; }
std::span<const StepperEntry> stepper_entries();
// The entry of a method; nullptr for a name no entry has.
const StepperEntry* find_stepper(std::string_view name);
// The entry of a method; InputError naming the methods there are for one no entry has.
const StepperEntry& stepper_entry(Method method);
std::optional<Method> find_method(std::string_view name);
std::string method_list();  // "rk4, dopri5, ..." for messages
// The methods whose entry passes keep, for messages: "colloc and tirk", "rk4 or dopri5";
// spell writes each name otherwise ("RK4", "{method=rk4}").
std::string method_names(bool (*keep)(const StepperEntry&), const char* conjunction,
                         std::string (*spell)(const char* name) = nullptr);
// InputError naming the methods there are for an unknown method.
std::unique_ptr<Stepper> make_stepper(Method method, const StepperSystem& system, const StepperSettings& settings);

}  // namespace mbsflow
