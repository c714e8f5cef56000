#include "mbsflow/runtime/run_request.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"

namespace mbsflow {
namespace {


Method method_named(const std::string& name, const char* setting) {
  const std::optional<Method> m = find_method(name);
  if (!m) throw InputError("{" + std::string(setting) + "=" + name + "}: unknown method (" + method_list() + ")");
  return *m;
}

}  // namespace

void apply_overrides(Model& m, const RunRequest& o) {
  if (o.t_start) m.simulation.t_start = *o.t_start;
  if (o.t_end) {
    if (!(*o.t_end > m.simulation.t_start)) throw InputError("{t_end}: must be > t_start of the model");
    m.simulation.t_end = *o.t_end;
  }
  if (o.method) {
    const Method method = method_named(*o.method, "method");
    if (m.simulation.method != method) {
      m.simulation.method = method;
      m.simulation.variant.clear();  // the model's variant belongs to its own method
    }
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

std::vector<Method> methods_named(const std::string& list) {
  std::vector<Method> out;
  for (const std::string& name : comma_items(list)) out.push_back(method_named(name, "submodel_methods"));
  return out;
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

void check_loose_request(const RunRequest& r) {
  const bool any_given = r.macro_step || r.coupling_tol || r.overlap || r.max_lag > 0 || r.exact_lag ||
                         !r.submodel_methods.empty();
  if (r.coupling != "loose" && any_given)
    throw InputError(
        "{macro_step}, {coupling_tol}, {max_lag}, {exact_lag}, {submodel_methods}, {overlap}: only with {coupling=loose}");
  if (r.exact_lag && r.max_lag == 0) throw InputError("{exact_lag}: needs {max_lag} L > 0");
}

LooseOptions loose_options(const RunRequest& r, double stable_step, double step, int threads) {
  // Many steps per exchange: the overlap keeps even stiff cut joints stable (loose_coupling.hpp).
  // A lag rules the overlap out: then a tenth of a step, well inside the joints' period.
  const double h = std::isfinite(stable_step) ? stable_step : step;
  const double macro_step = r.macro_step ? *r.macro_step : r.max_lag > 0 ? 0.1 * h : default_macro_steps * h;
  if (!std::isfinite(macro_step))
    throw InputError("{coupling=loose}: no joints to estimate a macro step from; give {macro_step}");
  const double tol = r.coupling_tol.value_or(r.max_lag > 0 || r.macro_step ? 0.0 : default_coupling_tol);
  LooseOptions lo{macro_step, r.extrapolation, threads, tol, r.max_lag, r.exact_lag, methods_named(r.submodel_methods)};
  if (r.overlap) lo.overlap = *r.overlap;
  return lo;
}

SettledRun settle_run(const Model& m, const RunRequest& r) {
  SettledRun s;
  s.stable = estimate_stable_step(m);
  s.options = options_from_model(m, s.stable.step);
  s.options.linear_solver = r.linear_solver;
  s.options.jacobian = r.jacobian;
  s.threads = run_threads(r.threads);
  check_loose_request(r);
  if (r.coupling == "loose") s.loose = loose_options(r, s.stable.step, s.options.step, s.threads);
  s.parallel = {s.threads, r.executor == "flow" ? Executor::flow_graph : Executor::barrier};
  return s;
}

}  // namespace mbsflow
