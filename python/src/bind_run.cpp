// mbsflow.run: a model run as `mbsflow run` runs it (the same defaults through
// run_request.hpp, so the same numbers), results to a file that mbsflow.Results reads.
#include <cmath>
#include <functional>
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
#include "mbsflow/runtime/run_settings.hpp"
#include "stop_guard.hpp"

namespace mbsflow::python {
namespace {

py::dict run_model(const Model& model, const std::string& output, const RunRequest& request, const py::object& progress) {
  Model m = model;
  apply_overrides(m, request);
  const SettledRun settled = settle_run(m, request);
  RunOptions o = settled.options;
  const bool loose = settled.loose.has_value();
  const int default_k = default_submodels(m, o.method, loose, settled.threads);
  RunPlan plan;
  plan.partition = cut_of_request(m, request, default_k, !loose);
  plan.loose = settled.loose;
  plan.parallel = settled.parallel;
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
    sink = std::make_unique<AsyncSink>(std::make_unique<Hdf5Sink>(output, parse_fields(request.fields), std::move(info)));
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
    out["macro_step"] = settled.loose->macro_step;
    out["macro_steps"] = stats.loose.macro_steps;
    out["max_coupling_error"] = stats.loose.max_position_error;
  }
  return out;
}

py::dict run_model_with(const Model& model, const std::string& output, const py::dict& settings,
                        const py::object& progress) {
  return run_model(model, output, request_of(settings, in_python, "mbsflow.run"), progress);
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("_run", &run_model_with, py::arg("model"), py::arg("output"), py::arg("settings"), py::arg("progress"));
  m.def(
      "_run_settings",
      [](const std::string& of) {
        if (of != "run" && of != "simulation") throw InputError("_run_settings: of run or simulation, not " + of);
        return settings_of(of == "run" ? in_python : in_simulation);
      },
      py::arg("of") = "run",
      "The settings mbsflow.run (or mbsflow.Simulation) takes: (keyword, default, help) each, in the order of "
      "run_settings().");
}

}  // namespace mbsflow::python
