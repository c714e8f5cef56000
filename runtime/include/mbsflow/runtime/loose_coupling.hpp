#pragma once
// Loose (GRID-style) coupling: every submodel integrates a macro step H on its own, with its
// own method and step, taking its neighbours' boundary bodies from a polynomial
// extrapolation of their last exchanged samples; at the end of the macro step the
// submodels exchange their boundary values. Jacobi-type: without a lag all submodels step
// from the same samples, so a run is repeatable; with a lag they may run ahead of each
// other. The difference between what a submodel extrapolated and what its neighbour then
// sent is the coupling error, reported per macro step.
#include <memory>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

struct LooseOptions {
  double macro_step = 0.0;  // H, a whole number of RunOptions::step for RK4
  int extrapolation = 1;    // polynomial order 0, 1 or 2 over the last 1, 2 or 3 samples
  int threads = 0;          // 0: all cores
  // > 0: adapt the macro step (at most macro_step) so that the coupling error (m, positions
  // of the neighbours' bodies at the cut) stays below this; a macro step above it is taken
  // again from its start with a shorter one. One process only.
  double coupling_tol = 0.0;
  // L > 0: a submodel may run up to L macro steps ahead of its slowest neighbour, taking
  // the newest neighbour values it has (asynchronous: the numbers depend on timing).
  // Fixed macro step only.
  int max_lag = 0;
  // With L > 0: take the neighbours' values exactly L macro steps back instead of the
  // newest, so that runs are repeatable whatever the timing.
  bool exact_lag = false;
  // Per submodel, its method (RK4 with substeps of RunOptions::step, or DOPRI5 with its
  // own steps); empty: RunOptions::method for all.
  std::vector<Method> methods;
  // Overlap (with_overlap's reach, s): each submodel also integrates the neighbours' bodies
  // that a disturbance at the cut reaches within this time, and extrapolates only beyond
  // them. < 0: overlap_factor macro steps; 0: none (extrapolated values at the cut).
  double overlap = -1.0;
};

struct LooseStats {
  long macro_steps = 0;
  // Per macro step: the largest distance between a ghost body's extrapolated and sent
  // position at its end (m), the largest velocity difference (m/s), and how many macro
  // steps old the neighbour values were that a submodel stepped from (largest).
  std::vector<double> position_error, velocity_error;
  std::vector<int> lag;
  std::vector<CouplingRecord> records;  // the same, as written to the results file
  double max_position_error = 0.0;
  int largest_lag = 0;
  long rejected = 0;  // macro steps taken again (adaptive)
  // Adaptive: macro steps taken with a coupling error above the tolerance at the smallest
  // macro step (smallest_macro_fraction of LooseOptions::macro_step).
  long over_tolerance = 0;
  double smallest_macro_step = 0.0, largest_macro_step = 0.0;
};

// Fills the per-macro-step vectors and extremes of stats from its records.
void summarise_records(LooseStats& stats);

// Any registered method inside each submodel (RK4: substeps of options.step; adaptive
// methods: their own steps, options.rtol/atol). Macro steps end on the output grid (see
// RunOptions; rounded onto the grid of options.step, macro steps shortened where needed),
// where the snapshots (global body order) are taken.
// InputError for a macro step that is not a positive time, an order outside 0..2, a
// negative lag, a lag with the adaptive macro step, or methods not one per submodel
// (submodels = 0: the count is not known yet).
void check_loose_options(const LooseOptions& loose, std::size_t submodels = 0);

// Defaults of a loose run: a macro step of this many RunOptions::step, and a coupling
// tolerance (m) for one-process runs without a lag.
inline constexpr int default_macro_steps = 16;
inline constexpr double default_coupling_tol = 1e-6;
// The adaptive macro step goes no lower than this fraction of LooseOptions::macro_step.
inline constexpr double smallest_macro_fraction = 1.0 / 1024.0;
// The automatic overlap, in macro steps of signal time.
inline constexpr double overlap_factor = 1.0;
// The overlap's reach (s) of these options: none with a lag (the borrowed bodies take their
// owners' values of the macro step's start, which a lagging run does not have).
double overlap_reach(const LooseOptions& loose);
// The decomposition a loose run integrates: d with the options' overlap.
Decomposition loose_decomposition(const Model& model, const Decomposition& d, const LooseOptions& loose);
// The RK4 stable step of the stiffest joint that d cuts (each joint alone, joint_rates);
// infinity if it cuts none.
double cut_joint_stable_step(const Model& model, const Decomposition& d);

RunSummary run_loose(const Model& model, const Decomposition& d, const RunOptions& options, const LooseOptions& loose,
                     ResultSink* sink, LooseStats* stats = nullptr);
// The same with a model the caller holds shared: the whole system (for the sink) shares it.
RunSummary run_loose(std::shared_ptr<const Model> model, const Decomposition& d, const RunOptions& options,
                     const LooseOptions& loose, ResultSink* sink, LooseStats* stats = nullptr);

}  // namespace mbsflow
