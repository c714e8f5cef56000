// mbsflow.run: a model run as `mbsflow run` runs it (the same defaults through
// run_request.hpp, so the same numbers), results to a file that mbsflow.Results reads.
#include <cmath>
#include <memory>

#include "bindings.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/partition_file.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/run.hpp"
#include "mbsflow/runtime/run_request.hpp"
#include "stop_guard.hpp"

namespace mbsflow::python {
namespace {

Method method_named(const std::string& name, const char* setting) {
  const std::optional<Method> m = find_method(name);
  if (!m) throw InputError("{" + std::string(setting) + "=" + name + "}: unknown method (" + method_list() + ")");
  return *m;
}

// The submodels: a partition file (str), a count (int), or the CLI's default (None).
std::optional<Decomposition> partition_of(const Model& m, const py::object& partition, Partitioner p, int default_k, bool loose) {
  if (py::isinstance<py::str>(partition)) return read_partition_file(m, partition.cast<std::string>());
  std::optional<int> given;
  if (!partition.is_none()) {
    given = partition.cast<int>();
    if (*given < 1) throw InputError("{partition=" + std::to_string(*given) + "}: at least 1 submodel");
  }
  return cut_for_run(m, given, default_k, p, !loose);
}

py::dict run_model(const Model& model, const std::string& output, const std::string& fields, const ModelOverrides& overrides,
                   const std::string& linear_solver, const std::string& jacobian, int threads_given,
                   const py::object& partition, const std::string& partitioner, const std::string& coupling,
                   const LooseRequest& loose_request, const std::string& executor, const py::object& progress) {
  Model m = model;
  apply_overrides(m, overrides);
  if (coupling != "tight" && coupling != "loose") throw InputError("{coupling=" + coupling + "}: tight or loose");
  if (executor != "flow" && executor != "barrier") throw InputError("{executor=" + executor + "}: flow or barrier");
  const StableStep stable = estimate_stable_step(m);
  RunOptions o = options_from_model(m, stable.step);
  o.linear_solver = linear_solver;
  o.jacobian = jacobian;
  const int threads = run_threads(threads_given);
  const bool loose = coupling == "loose";
  check_loose_request(loose, loose_request);
  const LooseOptions lo = loose ? loose_options(loose_request, stable.step, o.step, threads) : LooseOptions{};
  const int default_k = default_submodels(m, o.method, loose, threads);
  RunPlan plan;
  plan.partition = partition_of(m, partition, partitioner_named(partitioner), default_k, loose);
  if (loose) plan.loose = lo;
  plan.parallel = {threads, executor == "flow" ? Executor::flow_graph : Executor::barrier};
  if (!progress.is_none())
    o.progress = [&progress](double t, long steps) {
      py::gil_scoped_acquire gil;
      progress(t, steps);
    };
  std::unique_ptr<AsyncSink> sink;
  if (!output.empty()) {
    check_output_path(output, {{}, false, "output"});
    RunInfo info{model_to_json(m), method_name(o.method), o.step, o.t_start, o.t_end, o.output_every, "python: mbsflow.run"};
    info.output_interval = o.output_interval;
    sink = std::make_unique<AsyncSink>(std::make_unique<Hdf5Sink>(output, parse_fields(fields), std::move(info)));
  }
  StopGuard guard;
  o.stop = guard.flag();
  if (sink) sink->set_stop(o.stop);
  plan.options = o;
  RunSummary r;
  RunStats stats;
  try {
    py::gil_scoped_release release;
    r = mbsflow::run(m, plan, sink.get(), &stats);
    sink.reset();  // the file closed before Python reads it
  } catch (const RunError&) {
    sink.reset();
    guard.raise_if_signalled();
    throw;
  }
  py::dict out;
  out["steps"] = r.steps;
  out["rejected"] = r.rejected;
  out["evaluations"] = r.evaluations;
  out["jacobians"] = r.jacobians;
  out["factorizations"] = r.factorizations;
  out["snapshots"] = r.snapshots;
  out["wall_seconds"] = r.wall_seconds;
  out["final_state"] = to_numpy(r.final_state);
  out["method"] = std::string(method_name(o.method));
  out["step"] = o.step;
  out["t_start"] = o.t_start;
  out["t_end"] = o.t_end;
  out["submodels"] = plan.partition ? plan.partition->submodels.size() : std::size_t{1};
  if (loose) {
    out["macro_step"] = lo.macro_step;
    out["macro_steps"] = stats.loose.macro_steps;
    out["max_coupling_error"] = stats.loose.max_position_error;
  }
  return out;
}

}  // namespace

void bind_run(py::module_& m) {
  m.def(
      "_run",
      [](const Model& model, const std::string& output, const std::string& fields, std::optional<double> t_end,
         std::optional<double> step, std::optional<double> rtol, std::optional<double> atol,
         std::optional<double> output_interval, std::optional<int> output_every, std::optional<std::string> method,
         std::optional<std::string> variant, const std::string& linear_solver, const std::string& jacobian, int threads,
         const py::object& partition, const std::string& partitioner, const std::string& coupling,
         std::optional<double> macro_step, std::optional<double> coupling_tol, std::optional<double> overlap,
         int extrapolation, int max_lag, bool exact_lag, const std::vector<std::string>& submodel_methods,
         const std::string& executor, const py::object& progress, bool assemble) {
        ModelOverrides ov{t_end, step, rtol, atol, output_interval, output_every, std::nullopt, variant, assemble};
        if (method) ov.method = method_named(*method, "method");
        LooseRequest lr{macro_step, coupling_tol, overlap, extrapolation, max_lag, exact_lag, {}};
        for (const std::string& s : submodel_methods) lr.methods.push_back(method_named(s, "methods"));
        return run_model(model, output, fields, ov, linear_solver, jacobian, threads, partition, partitioner, coupling, lr,
                         executor, progress);
      },
      py::arg("model"), py::arg("output"), py::arg("fields"), py::arg("t_end"), py::arg("step"), py::arg("rtol"),
      py::arg("atol"), py::arg("output_interval"), py::arg("output_every"), py::arg("method"), py::arg("variant"),
      py::arg("linear_solver"), py::arg("jacobian"), py::arg("threads"), py::arg("partition"), py::arg("partitioner"),
      py::arg("coupling"), py::arg("macro_step"), py::arg("coupling_tol"), py::arg("overlap"), py::arg("extrapolation"),
      py::arg("max_lag"), py::arg("exact_lag"), py::arg("submodel_methods"), py::arg("executor"), py::arg("progress"),
      py::arg("assemble") = false);
}

}  // namespace mbsflow::python
