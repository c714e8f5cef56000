#pragma once
// What a front end (the CLI, the Python module) asks of a run in its users' terms, and the
// defaults that turn it into settings: one piece of code for both, so that the same request
// gives the same run, bit for bit.
#include <optional>
#include <string>
#include <vector>

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

// InputError for loose settings in a tight run, or an exact lag without a lag.
void check_loose_request(bool loose, const LooseRequest& request);

// The loose options of a request: the macro step default_macro_steps RK4 stable steps
// (stable_step, else `step` when the model has no joints to estimate it from), a tenth of
// one with a lag (then no overlap); error control with default_coupling_tol unless a lag or
// a macro step was given (a given macro step alone is a fixed one).
LooseOptions loose_options(const LooseRequest& request, double stable_step, double step, int threads);

}  // namespace mbsflow
