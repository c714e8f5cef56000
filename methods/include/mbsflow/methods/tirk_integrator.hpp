#pragma once
// Implicit Runge-Kutta methods iterated in parallel through a triangular (seed 004) or
// diagonal approximation T of their matrix A. Every scheme is the splitting iteration
//
//   Y_i - tau t_ii f(Y_i) = x_n + tau sum_j (A - T)_ij F_j^(nu-1) + tau sum_{j<i} t_ij F_j^(nu),
//
// whose fixed point is the Runge-Kutta solution itself (so the tableau's order is kept),
// with Y_i the stage values, F_j = f(t_n + c_j tau, Y_j), and T = T_L (triangular: stage i
// waits for the stages j < i of the same iteration), T = D (diagonal: all stages at
// once) or T = 0 (Jacobi: the full matrix, explicit, all stages at once). The stage
// equation is solved
//   - by fixed-point substitution (functional: jacobi, triangular, diagonal) for
//     non-stiff problems, which contracts for tau < 1 / (L M),
//     M = max_i sum_j |(A - T)_ij| + max_i sum_j |t_ij|, L the Lipschitz constant of f;
//   - by one simplified Newton step with I - tau t_ii J (newton-triangular = PTIRK,
//     newton-diagonal = PDIRK, after van der Houwen, Sommeijer and de Swart), one
//     factorisation per distinct t_ii, for stiff problems;
//   - or, with no splitting at all, by the full simplified Newton iteration with I - tau A (x) J
//     split by the eigenvalues of A (newton, as Radau5: one real and one complex system
//     for 3-stage Radau IIA), whose iteration contracts like Newton's.
// Stages (and slices of equations) are nodes of a oneTBB flow graph; the numbers do not
// depend on the thread count.
#include "mbsflow/error.hpp"
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mbsflow/methods/block_integrator.hpp"
#include "mbsflow/methods/rk_tableau.hpp"

namespace mbsflow {

enum class TirkIteration { jacobi, triangular, diagonal, newton_triangular, newton_diagonal, newton };
const char* to_string(TirkIteration i);
TirkIteration tirk_iteration_from_string(const std::string& name);  // throws InputError
bool is_newton(TirkIteration i);

// The approximation T of the implicit block of A that an iteration uses (not for newton,
// which uses A itself).
Eigen::MatrixXd splitting_matrix(const TriangularSplitting& split, TirkIteration i);
// M of the contraction bound tau < 1 / (L M) of the functional iteration with T.
double contraction_constant(const Eigen::MatrixXd& a, const Eigen::MatrixXd& t);

// The Newton iteration stops when its estimated error is this fraction of the tolerance.
// On a small system (below 1000 equations) whose Jacobian costs a few f evaluations
// (cheap_jacobian), Radau5's (and scipy's) max(10 eps / rtol, min(0.03, sqrt(rtol))): the
// iteration is carried further at tight tolerances, which gains digits at the same cost.
// Elsewhere max(10 eps / rtol, 0.03): on the multibody models, whose Jacobians are dear,
// the sqrt rule cost ~20 % more f evaluations at equal error (2000-body chain).
double newton_tolerance(double rtol, bool cheap_jacobian);

struct TirkSettings {
  std::string tableau = "radau3";
  // The full Newton iteration by default: on the stiff multibody models and the seed's
  // problems it needs a third of the triangular iteration's f evaluations (docs/methods.md, "Current figures").
  TirkIteration iteration = TirkIteration::newton;
  double rtol = 1e-6, atol = 1e-6;
  // Per-component tolerances (one value per equation), in place of rtol / atol when not
  // empty. The error is measured in the weighted RMS norm with w_i = atol_i + rtol_i |y_i|.
  Eigen::VectorXd rtols, atols;
  double safety = 0.9, facmin = 0.2, facmax = 4.0;
  // Gustafsson's predictive step control after accepted steps, as Radau5 (the smaller of
  // its factor and the classical one); false: the classical controller alone.
  bool predictive = true;
  double initial_step = 0;  // 0: chosen from the problem
  double fixed_step = 0;    // > 0: no step control
  double min_step = 0;      // 0: 10 eps |t| (Radau5's limit)
  long max_steps = 10'000'000;
  int max_iterations = 0;    // 0: 10 for Newton-type, 50 for functional iterations
  int fixed_iterations = 0;  // > 0: exactly this many iterations per step, no convergence test
  // Functional triangular/diagonal: substitutions per stage and iteration for the stage's
  // own term tau t_ii f(Y_i) (each one f evaluation). With 1 the diagonal scheme is Jacobi.
  int inner_iterations = 3;
  // Stop when the estimated iteration error is this fraction of the tolerance; 0:
  // newton_tolerance(rtol).
  double iteration_tol = 0;
  // Full Newton iteration: the matrices factorised for step tau_f serve a step tau while
  // |tau / tau_f - 1| <= this (a slightly stale Newton matrix, as CVODE keeps one while
  // gamma changes by less than 30 %); 0: refactorise at every change of step.
  double refactor_ratio = 0.2;
  bool finite_difference_jacobian = false;
  LinearSolverKind linear_solver = LinearSolverKind::automatic;
  int threads = 0;              // 0: all cores; 1: sequential (the same numbers)
  Eigen::Index slice_size = 0;  // equations per slice; 0: 4096 once a system has 8192 or more
};

struct TirkStats {
  long steps = 0, accepted = 0, rejected = 0, iteration_failures = 0;
  long rhs_evaluations = 0, jacobians = 0, factorizations = 0, iterations = 0;
  LinearSolverKind linear_solver = LinearSolverKind::dense;
  double contraction_m = 0;       // M of the scheme
  double lipschitz_start = 0;     // ||J(t0, y0)||_inf (computed for the functional schemes too)
  double lipschitz_observed = 0;  // largest |F^nu - F^(nu-1)| / |Y^nu - Y^(nu-1)| seen in the iterations
  double largest_step = 0;        // largest accepted step
};

struct TirkResult {
  TirkStats stats;
  std::vector<BlockStepRecord> steps;  // taken = stages of an accepted step, 0 rejected
  double t = 0;
  Eigen::VectorXd y;
};

// Integrates from problem.t0 to problem.t_end; on_step (optional) sees every accepted
// step's end point. Throws InputError for bad settings, RunError when
// the step falls below the minimum (a functional iteration that diverges at a fixed step
// says so, with its contraction bound) or max_steps is reached.
TirkResult integrate_tirk(const OdeProblem& problem, const TirkSettings& settings,
                          const std::function<void(double t, const Eigen::VectorXd& y)>& on_step = {});

// The measurement of the seed's claim: one step of size tau from (t, x), started from
// the trivial predictor Y_i = x, iterated `count` times with fixed_iterations; error[nu-1] =
// max_i |Y_i^nu - Y_i*|_inf / max(1, |Y*|_inf) after iteration nu, against the converged
// stage values Y* (newton-triangular iterated to rounding). evaluations[nu-1]: f
// evaluations spent so far. reference_ok: Y* converged (its stage residual is reported).
struct IterationTrace {
  std::vector<double> error;
  std::vector<long> evaluations;
  bool reference_ok = false;
  double reference_residual = 0;
};
// integrate_tirk step by step, with the same numbers: the engine of the "tirk" stepper.
// As BlockIntegrator: begin() reads the problem's t0, y0 and t_end again; project maps
// every accepted step's end onto the state's manifold.
class TirkIntegrator {
 public:
  TirkIntegrator(const OdeProblem& problem, const TirkSettings& settings,
                 std::function<void(double t, Eigen::VectorXd& y)> project = {});
  ~TirkIntegrator();
  void begin();
  bool advance();  // one accepted step; false when problem.t_end is reached
  double t() const;
  const Eigen::VectorXd& y() const;
  double next_step() const;
  const TirkStats& stats() const;
  // Cubic Hermite dense output in the last accepted step (third order).
  void dense(double t, Eigen::VectorXd& out) const;
  // Checkpoints, between steps (mbsflow/methods/stepper.hpp).
  void save(StateWriter& out) const;
  void restore(StateReader& in);

  class Driver;

 private:
  std::unique_ptr<Driver> d_;
  friend TirkResult integrate_tirk(const OdeProblem&, const TirkSettings&,
                                   const std::function<void(double, const Eigen::VectorXd&)>&);
};

IterationTrace trace_tirk_iterations(const OdeProblem& problem, const TirkSettings& settings, double t,
                                     const Eigen::VectorXd& x, double tau, int count);

}  // namespace mbsflow
