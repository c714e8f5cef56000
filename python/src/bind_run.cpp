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

// The setting of Python's keyword `keyword`, or null.
const RunSetting* python_setting(const std::string& keyword) {
  for (const RunSetting& s : run_settings())
    if ((s.places & in_python) && keyword == s.keyword()) return &s;
  return nullptr;
}

// A request from mbsflow.run's keywords, each checked as its declaration says: its type,
// range or choices (InputError naming it and its value).
RunRequest request_of(const py::dict& settings) {
  RunRequest r;
  for (const auto& [key, value] : settings) {
    const std::string keyword = key.cast<std::string>();
    const RunSetting* s = python_setting(keyword);
    if (!s) throw InputError("mbsflow.run: no setting " + keyword);
    // A list is shown as the message's list, "a,b" (rendered [a, b]).
    std::string shown;
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value))
      for (const py::handle item : value) shown += (shown.empty() ? "" : ",") + py::str(item).cast<std::string>();
    else
      shown = py::str(value).cast<std::string>();
    auto fail = [&](const std::string& what) { throw InputError("{" + std::string(s->name) + "=" + shown + "}: " + what); };
    if (value.is_none()) continue;  // the default, as not given
    // Python's partition is a count or a partition file.
    if (std::string(s->name) == "partitions" && (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"))) {
      r.partition_file = py::module_::import("os").attr("fspath")(value).cast<std::string>();
      continue;
    }
    struct Read {
      const RunSetting& s;
      const py::handle value;
      std::function<void(const std::string&)> fail;
      bool flag() const {
        if (!py::isinstance<py::bool_>(value)) fail("must be True or False");
        return value.cast<bool>();
      }
      double number() const {
        const bool ok = !py::isinstance<py::bool_>(value) &&
                        (py::isinstance<py::int_>(value) || (!s.is_integer() && py::isinstance<py::float_>(value)));
        if (!ok) fail(s.is_integer() ? "must be an integer" : "must be a number");
        return value.cast<double>();
      }
      std::string text() const {
        std::string t;
        if (s.list && (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value))) {
          for (const py::handle item : value) {
            if (!py::isinstance<py::str>(item)) fail("must be a list of names");
            t += (t.empty() ? "" : ",") + item.cast<std::string>();
          }
        } else if (!py::isinstance<py::str>(value)) {
          fail("must be a string");
        } else {
          t = value.cast<std::string>();
        }
        return t;
      }
    };
    set_setting(*s, r, Read{*s, value, fail});
  }
  return r;
}

// Python's default of a setting: None where it has none.
py::object python_default(const RunSetting& s) {
  const RunRequest r;
  return std::visit(
      [&](auto member) -> py::object {
        const auto& v = r.*member;
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, bool> || std::is_same_v<V, int> || std::is_same_v<V, double> ||
                      std::is_same_v<V, std::string>)
          return py::cast(v);
        else
          return py::none();
      },
      s.field);
}

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
  return run_model(model, output, request_of(settings), progress);
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("_run", &run_model_with, py::arg("model"), py::arg("output"), py::arg("settings"), py::arg("progress"));
  m.def(
      "_run_settings",
      [] {
        py::list out;
        for (const RunSetting& s : run_settings())
          if (s.places & in_python)
            out.append(py::make_tuple(s.keyword(), python_default(s), render(s.help, keyword_for)));
        return out;
      },
      "The settings mbsflow.run takes: (keyword, default, help) each, in the order of run_settings().");
}

}  // namespace mbsflow::python
