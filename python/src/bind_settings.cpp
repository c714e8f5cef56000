// The run settings' Python keywords (mbsflow.run, mbsflow.Simulation): read from their
// declarations (mbsflow/runtime/run_settings.hpp), each checked as declared.
#include <functional>

#include "bindings.hpp"
#include "mbsflow/runtime/run_settings.hpp"

namespace mbsflow::python {
namespace {

// The setting of Python's keyword `keyword` given at `place`, or null.
const RunSetting* python_setting(const std::string& keyword, unsigned place) {
  for (const RunSetting& s : run_settings())
    if ((s.places & place) && keyword == s.keyword()) return &s;
  return nullptr;
}

}  // namespace

RunRequest request_of(const py::dict& settings, unsigned place, const char* caller) {
  RunRequest r;
  for (const auto& [key, value] : settings) {
    const std::string keyword = key.cast<std::string>();
    const RunSetting* s = python_setting(keyword, place);
    if (!s) throw InputError(std::string(caller) + ": no setting " + keyword);
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

namespace {

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

}  // namespace

py::list settings_of(unsigned place) {
  py::list out;
  for (const RunSetting& s : run_settings())
    if (s.places & place) out.append(py::make_tuple(s.keyword(), python_default(s), render(s.help, keyword_for)));
  return out;
}

}  // namespace mbsflow::python
