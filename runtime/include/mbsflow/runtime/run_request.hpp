#pragma once
// What a front end (the CLI, the Python module) asks of a run in its users' terms, and the
// defaults that turn it into settings: one piece of code for both, so that the same request
// gives the same run, bit for bit.
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"

namespace mbsflow {

// Settings that replace the model's simulation block.
struct ModelOverrides {
  std::optional<double> t_end, step, rtol, atol, output_interval;
  std::optional<int> output_every;  // replaces an output interval too
  std::optional<Method> method;     // another method than the model's drops the model's variant
  std::optional<std::string> variant;
  bool assemble = false;  // move the bodies onto violated rigid joints (else they are refused)
};

// InputError for a t_end not after the model's t_start.
void apply_overrides(Model& model, const ModelOverrides& overrides);

// What a loose run was asked for; unset: the defaults.
struct LooseRequest {
  std::optional<double> macro_step, coupling_tol, overlap;
  int extrapolation = 1;
  int max_lag = 0;
  bool exact_lag = false;
  std::vector<Method> methods;  // per submodel
  bool any_given() const {
    return macro_step || coupling_tol || overlap || max_lag > 0 || exact_lag || !methods.empty();
  }
};

// The threads of a run on this process: the given count, or all cores (0).
int run_threads(int given);

// How many submodels a run on this process's threads is cut into by default: one per
// thread (fewer for a small model) where they exchange a method's stages or run loosely
// coupled, else 1 (an implicit method's stages are parallel inside its step).
int default_submodels(const Model& model, Method method, bool loose, int threads);

// The cut of a run: `given` submodels, or default_k; none where neither asks for more
// than one and a plain run is what one submodel means (a tight run in one process).
std::optional<Decomposition> cut_for_run(const Model& model, std::optional<int> given, int default_k,
                                         Partitioner partitioner, bool plain_if_one);

// InputError for loose settings in a tight run, or an exact lag without a lag.
void check_loose_request(bool loose, const LooseRequest& request);

// The loose options of a request: the macro step default_macro_steps RK4 stable steps
// (stable_step, else `step` when the model has no joints to estimate it from), a tenth of
// one with a lag (then no overlap); error control with default_coupling_tol unless a lag or
// a macro step was given (a given macro step alone is a fixed one).
LooseOptions loose_options(const LooseRequest& request, double stable_step, double step, int threads);

}  // namespace mbsflow
