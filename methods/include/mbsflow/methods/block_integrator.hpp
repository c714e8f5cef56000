#pragma once
// Integration of an OdeProblem with collocation block methods and the seed's parallel step
// control: the s-point and the (s+1)-point block are computed side by side from the same
// start and step (two subgraphs of one oneTBB flow graph, one node per block point and
// slice of equations); their difference at the points they share (the s points of
// equidistant blocks, the common end of blocks at Radau points) decides: within the global
// tolerance the (s+1)-point solution is taken, within the local tolerance the s-point one,
// otherwise the step is cut.
#include "mbsflow/error.hpp"
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mbsflow/methods/block_method.hpp"
#include "mbsflow/methods/ode_problem.hpp"
#include "mbsflow/methods/shifted_solver.hpp"
#include "mbsflow/methods/state_archive.hpp"

namespace mbsflow {

enum class BlockIteration { functional, newton };
const char* to_string(BlockIteration i);
BlockIteration block_iteration_from_string(const std::string& name);  // throws InputError

struct BlockSettings {
  // The s-point method; the (s+1)-point one has order + 1 (or its maximal order) and the
  // same nodes. Default: Radau points, s = 3 (L-stable blocks of order 5 and 7).
  BlockMethodSpec method = default_block_method();
  double rtol = 1e-6, atol = 1e-6;
  // Per-component tolerances (one value per equation), in place of rtol / atol when not
  // empty. The error is measured in the weighted RMS norm with w_i = atol_i + rtol_i |y_i|.
  Eigen::VectorXd rtols, atols;
  // The (s+1)-point block is taken when the scaled difference is at most this fraction of
  // the tolerance (the seed's global tolerance); the step controller aims at it. 0: 0.1
  // for equidistant blocks (the seed's choice), 1 for Radau points, whose difference at
  // the end is the s-point block's own error (so the higher-order block is always taken,
  // as an embedded pair does).
  double global_fraction = 0;
  double safety = 0.9, facmin = 0.2, facmax = 4.0;
  // Gustafsson's predictive step control after accepted steps, as Radau5 (the smaller of
  // its factor and the classical one); false: the classical controller alone.
  bool predictive = true;
  double initial_step = 0;  // 0: chosen from the problem (Hairer-Wanner's starting step)
  double fixed_step = 0;    // > 0: no step control, the s-point method alone with this step
  double min_step = 0;      // 0: 10 eps |t| (Radau5's limit)
  long max_steps = 10'000'000;
  BlockIteration iteration = BlockIteration::newton;
  int max_iterations = 0;       // 0: 7 for Newton, 50 for functional iteration
  double iteration_tol = 0.03;  // stop when the estimated iteration error is this fraction of the tolerance
  // Newton: the matrices factorised for step tau_f serve a step tau while |tau / tau_f - 1|
  // <= this (as TirkSettings::refactor_ratio); 0: refactorise at every change of step.
  double refactor_ratio = 0.2;
  bool finite_difference_jacobian = false;
  LinearSolverKind linear_solver = LinearSolverKind::automatic;
  int threads = 0;                // 0: all cores; 1: sequential (the same numbers)
  Eigen::Index slice_size = 0;    // equations per slice; 0: 4096 once a system has 8192 or more
};

// One step attempt, for output.
struct BlockStepRecord {
  double t = 0, tau = 0;  // start and point spacing
  int taken = 0;          // points taken: s + 1, s, or 0 (rejected)
  double error = 0;       // scaled difference of the two blocks (1 = the local tolerance)
  int iterations_s = 0, iterations_s1 = 0;
  bool iteration_failed = false;
};

struct BlockStats {
  long steps = 0, accepted = 0, rejected = 0, taken_s1 = 0, taken_s = 0, iteration_failures = 0;
  long rhs_evaluations = 0, jacobians = 0, factorizations = 0, iterations = 0;
  LinearSolverKind linear_solver = LinearSolverKind::dense;
};

// An accepted block: its points, and the collocation polynomial through them.
struct AcceptedBlock {
  double t0 = 0, tau = 0;
  int points = 0;
  const BlockCoefficients* method = nullptr;
  const std::vector<Eigen::VectorXd>* past_u = nullptr;  // m values at t0 - (m-1) tau .. t0
  const std::vector<Eigen::VectorXd>* past_f = nullptr;
  const std::vector<Eigen::VectorXd>* u = nullptr;  // values at t0 + positions(i) tau, i = 1..points
  const std::vector<Eigen::VectorXd>* f = nullptr;
  Eigen::VectorXd interpolate(double t) const;  // dense output, t in [t0 - (m-1) tau, t0 + span tau]
};

struct BlockResult {
  BlockStats stats;
  std::vector<BlockStepRecord> steps;
  double t = 0;
  Eigen::VectorXd y;
};

// Integrates from problem.t0 to problem.t_end. on_block (optional) sees every accepted
// block. Throws InputError for bad settings and RunError when the
// step falls below the minimum or max_steps is reached.
BlockResult integrate_block(const OdeProblem& problem, const BlockSettings& settings,
                            const std::function<void(const AcceptedBlock&)>& on_block = {});

// integrate_block block by block, with the same numbers: the engine of the "colloc"
// stepper. The problem and settings are kept by reference; begin() reads the problem's
// t0, y0 and t_end (and the settings' initial_step) again, so a caller may change them
// and begin anew. project (optional) maps every accepted block's end point onto the
// state's manifold before the next block starts from it.
class BlockIntegrator {
 public:
  BlockIntegrator(const OdeProblem& problem, const BlockSettings& settings,
                  std::function<void(const AcceptedBlock&)> on_block = {},
                  std::function<void(double t, Eigen::VectorXd& y)> project = {});
  ~BlockIntegrator();
  void begin();
  bool advance();  // one accepted block; false when problem.t_end is reached
  double t() const;
  const Eigen::VectorXd& y() const;
  double next_step() const;  // the point spacing the next block tries
  const BlockStats& stats() const;
  // Checkpoints, between blocks (mbsflow/methods/stepper.hpp).
  void save(StateWriter& out) const;
  void restore(StateReader& in);

 private:
  class Driver;
  std::unique_ptr<Driver> d_;
  friend BlockResult integrate_block(const OdeProblem&, const BlockSettings&, const std::function<void(const AcceptedBlock&)>&);
};

}  // namespace mbsflow
