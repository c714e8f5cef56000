#include "mbsflow/runtime/run_request.hpp"

#include <cmath>
#include <thread>

#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"

namespace mbsflow {

void apply_overrides(Model& m, const ModelOverrides& o) {
  if (o.t_end) {
    if (!(*o.t_end > m.simulation.t_start)) throw InputError("{t_end}: must be > t_start of the model");
    m.simulation.t_end = *o.t_end;
  }
  if (o.method && m.simulation.method != *o.method) {
    m.simulation.method = *o.method;
    m.simulation.variant.clear();  // the model's variant belongs to its own method
  }
  if (o.variant) m.simulation.variant = *o.variant;
  if (o.rtol) m.simulation.rtol = *o.rtol;
  if (o.atol) m.simulation.atol = *o.atol;
  if (o.step) m.simulation.step = *o.step;
  if (o.output_every) {
    m.simulation.output_every = *o.output_every;
    m.simulation.output_interval.reset();
  }
  if (o.output_interval) m.simulation.output_interval = *o.output_interval;
  if (o.assemble) m.simulation.assemble = true;
}

int run_threads(int given) { return given > 0 ? given : static_cast<int>(std::thread::hardware_concurrency()); }

int default_submodels(const Model& m, Method method, bool loose, int threads) {
  return has_stage_scheme(stepper_entry(method)) || loose ? default_partitions(m, threads) : 1;
}

std::optional<Decomposition> cut_for_run(const Model& m, std::optional<int> given, int default_k, Partitioner p,
                                         bool plain_if_one) {
  const int k = given.value_or(default_k);
  if (k == 1 && !given && plain_if_one) return std::nullopt;
  return decompose(m, k, p);
}

void check_loose_request(bool loose, const LooseRequest& r) {
  if (!loose && r.any_given())
    throw InputError("{macro_step}, {coupling_tol}, {max_lag}, {exact_lag}, {methods}, {overlap}: only with {coupling=loose}");
  if (r.exact_lag && r.max_lag == 0) throw InputError("{exact_lag}: needs {max_lag} L > 0");
}

LooseOptions loose_options(const LooseRequest& r, double stable_step, double step, int threads) {
  // Many steps per exchange: the overlap keeps even stiff cut joints stable (loose_coupling.hpp).
  // A lag rules the overlap out: then a tenth of a step, well inside the joints' period.
  const double h = std::isfinite(stable_step) ? stable_step : step;
  const double macro_step = r.macro_step ? *r.macro_step : r.max_lag > 0 ? 0.1 * h : default_macro_steps * h;
  if (!std::isfinite(macro_step))
    throw InputError("{coupling=loose}: no joints to estimate a macro step from; give {macro_step}");
  const double tol = r.coupling_tol.value_or(r.max_lag > 0 || r.macro_step ? 0.0 : default_coupling_tol);
  LooseOptions lo{macro_step, r.extrapolation, threads, tol, r.max_lag, r.exact_lag, r.methods};
  if (r.overlap) lo.overlap = *r.overlap;
  return lo;
}

}  // namespace mbsflow
