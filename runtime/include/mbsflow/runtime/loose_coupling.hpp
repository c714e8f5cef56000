#pragma once
// Loose (GRID-style) coupling: every submodel integrates a macro step H on its own, with its
// own method and step, taking its neighbours' boundary bodies from a polynomial
// extrapolation of their last exchanged samples; at the end of the macro step the
// submodels exchange their boundary values. Jacobi-type: all submodels step from the same
// samples, so a run is repeatable. The difference between what a submodel extrapolated
// and what its neighbour then sent is the coupling error, reported per macro step.
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

struct LooseOptions {
  double macro_step = 0.0;  // H, a whole number of RunOptions::step for RK4
  int extrapolation = 1;    // polynomial order 0, 1 or 2 over the last 1, 2 or 3 samples
  int threads = 0;          // 0: all cores
  // > 0: adapt the macro step so that the coupling error (m, ghost positions) stays below
  // this; a macro step above it is taken again from its start with a shorter one.
  double coupling_tol = 0.0;
  // L > 0: a macro step takes its neighbours' values from L macro steps further back, so a
  // submodel may run L macro steps ahead of its neighbours and their messages may travel
  // meanwhile. Always exactly L back (not the newest that happens to be in): runs stay
  // repeatable. Fixed macro step only.
  int max_lag = 0;
};

struct LooseStats {
  long macro_steps = 0;
  // Per macro step: the largest distance between a ghost body's extrapolated and sent
  // position at the end of the step (m), and its largest relative velocity difference.
  std::vector<double> position_error, velocity_error;
  double max_position_error = 0.0;
  long rejected = 0;  // macro steps taken again (adaptive)
  double smallest_macro_step = 0.0, largest_macro_step = 0.0;
};

// RK4 (substeps of options.step) or DOPRI5 (its own steps, options.rtol/atol) inside each
// submodel. Macro steps end on the output grid (every options.output_every * options.step,
// shortened where needed), where the snapshots (global body order) are taken.
// InputError for a macro step that is not a positive time, an order outside 0..2, a
// negative lag or a lag with the adaptive macro step.
void check_loose_options(const LooseOptions& loose);

RunSummary run_loose(const Model& model, const Decomposition& d, const RunOptions& options, const LooseOptions& loose,
                     ResultSink* sink, LooseStats* stats = nullptr);

}  // namespace mbsflow
