#include "options_json.hpp"

#include <limits>
#include <type_traits>
#include <variant>

#include "mbsflow/error.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/run_settings.hpp"
#include "sink_runner.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;

// A field of the options a coordinator sends, under its key: the options' member name,
// which is the run setting's declared name (or its library_name) where the field is a
// setting's. One table per options struct writes and reads them, so that a field cannot be
// sent and not read.
template <class O>
struct Sent {
  const char* key;
  std::variant<double O::*, int O::*, bool O::*, std::string O::*, Method O::*, std::vector<Method> O::*> field;
};

const Sent<RunOptions> run_fields[] = {
    {"method", &RunOptions::method},         {"variant", &RunOptions::variant},
    {"linear_solver", &RunOptions::linear_solver}, {"jacobian", &RunOptions::jacobian},
    {"t_start", &RunOptions::t_start},       {"t_end", &RunOptions::t_end},
    {"step", &RunOptions::step},             {"step_given", &RunOptions::step_given},
    {"fixed_step", &RunOptions::fixed_step}, {"output_every", &RunOptions::output_every},
    {"output_interval", &RunOptions::output_interval}, {"rtol", &RunOptions::rtol},
    {"atol", &RunOptions::atol}};

// Loose coupling: threads stay with the process that runs the macro steps.
const Sent<LooseOptions> loose_fields[] = {
    {"macro_step", &LooseOptions::macro_step}, {"extrapolation", &LooseOptions::extrapolation},
    {"max_lag", &LooseOptions::max_lag},       {"exact_lag", &LooseOptions::exact_lag},
    {"methods", &LooseOptions::methods},       {"overlap", &LooseOptions::overlap},
    {"coupling_tol", &LooseOptions::coupling_tol}};

Method method_of(const std::string& name) {
  const std::optional<Method> m = find_method(name);
  if (!m) throw InputError("the coordinator asked for an unknown method " + name);
  return *m;
}

// An integer of the message in its setting's declared range: a number that is not one
// (1e300, 2.5) is refused, never converted.
int integer(const json& v, const char* key, const char* what) {
  long long lo = std::numeric_limits<int>::min(), hi = std::numeric_limits<int>::max();
  if (const RunSetting* s = find_run_setting(key)) {
    lo = std::max(lo, static_cast<long long>(std::max(s->lo, -1e18)));
    hi = std::min(hi, static_cast<long long>(std::min(s->hi, 1e18)));
  }
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
    throw InputError(std::string(what) + ": " + key + " is not an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  return static_cast<int>(v.get<long long>());
}

template <class O, std::size_t N>
json to_json(const O& o, const Sent<O> (&fields)[N]) {
  json j = json::object();
  for (const Sent<O>& f : fields)
    std::visit(
        [&](auto member) {
          const auto& v = o.*member;
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<V, Method>) {
            j[f.key] = method_name(v);
          } else if constexpr (std::is_same_v<V, std::vector<Method>>) {
            json names = json::array();
            for (Method m : v) names.push_back(method_name(m));
            j[f.key] = names;
          } else {
            j[f.key] = v;
          }
        },
        f.field);
  return j;
}

// Reads every field of the table (InputError for a missing one or of the wrong type, with
// `what` first), then checks the whole with check() as a run started here checks it.
template <class O, std::size_t N, class Check>
O from_json(const json& j, const Sent<O> (&fields)[N], const char* what, Check check) {
  O o;
  try {
    for (const Sent<O>& f : fields)
      std::visit(
          [&](auto member) {
            auto& v = o.*member;
            using V = std::decay_t<decltype(v)>;
            const json& x = j.at(f.key);
            if constexpr (std::is_same_v<V, Method>) {
              v = method_of(x.get<std::string>());
            } else if constexpr (std::is_same_v<V, std::vector<Method>>) {
              v.clear();
              for (const std::string& name : x.get<std::vector<std::string>>()) v.push_back(method_of(name));
            } else if constexpr (std::is_same_v<V, int>) {
              v = integer(x, f.key, what);
            } else {
              v = x.get<V>();
            }
          },
          f.field);
  } catch (const json::exception& e) {
    throw InputError(std::string(what) + ": " + e.what());
  }
  try {
    check(o);
  } catch (const InputError& e) {
    throw InputError(std::string(what) + ": " + e.text());
  }
  return o;
}

}  // namespace

json options_to_json(const RunOptions& o) { return to_json(o, run_fields); }

RunOptions options_from_json(const json& j) {
  return from_json(j, run_fields, "run options from the coordinator", [](const RunOptions& o) { check_options(o); });
}

json loose_to_json(const LooseOptions& l) { return to_json(l, loose_fields); }

LooseOptions loose_from_json(const json& j) {
  return from_json(j, loose_fields, "loose-coupling options from the coordinator",
                   [](const LooseOptions& l) { check_loose_options(l); });
}

}  // namespace mbsflow
