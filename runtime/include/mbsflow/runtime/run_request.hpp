#pragma once
// What a front end (the CLI, the Python module) asks of a run in its users' terms, and the
// defaults that turn it into settings: one piece of code for both, so that the same request
// gives the same run, bit for bit.
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/run_settings.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

// The model's simulation block with the request's settings of it (run_settings.hpp's
// in_model ones) in place of its own: another method drops the model's variant, an
// output_every drops its output interval. InputError for a t_end not after t_start or an
// unknown method.
void apply_overrides(Model& model, const RunRequest& request);

// The methods of a comma-separated list ({submodel_methods}); InputError naming an unknown one.
std::vector<Method> methods_named(const std::string& list);

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
void check_loose_request(const RunRequest& request);

// The loose options of a request: the macro step default_macro_steps RK4 stable steps
// (stable_step, else `step` when the model has no joints to estimate it from), a tenth of
// one with a lag (then no overlap); error control with default_coupling_tol unless a lag or
// a macro step was given (a given macro step alone is a fixed one).
LooseOptions loose_options(const RunRequest& request, double stable_step, double step, int threads);

// A run's settings from a request, on a model that apply_overrides has given the request's
// simulation settings: the options (method, step, grid, tolerances, linear algebra), the
// threads and, for a loosely coupled run, the loose options. The CLI and Python settle a
// run here, so that the same request gives the same run.
struct SettledRun {
  StableStep stable;
  RunOptions options;
  int threads = 1;
  std::optional<LooseOptions> loose;
  ParallelOptions parallel;  // threads and executor
};
SettledRun settle_run(const Model& model, const RunRequest& request);

}  // namespace mbsflow
