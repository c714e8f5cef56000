#include "options_json.hpp"

#include <limits>

#include "mbsflow/error.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "sink_runner.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;

Method method_of(const std::string& name) {
  const std::optional<Method> m = find_method(name);
  if (!m) throw InputError("the coordinator asked for an unknown method " + name);
  return *m;
}

// An integer of the message in [lo, hi]: a number that is not one (1e300, 2.5) is refused,
// never converted.
int integer(const json& j, const char* key, int lo = std::numeric_limits<int>::min(), int hi = std::numeric_limits<int>::max()) {
  const json& v = j.at(key);
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
    throw InputError(std::string("run options from the coordinator: ") + key + " is not an integer in [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return static_cast<int>(v.get<long long>());
}

}  // namespace

json options_to_json(const RunOptions& o) {
  return {{"method", method_name(o.method)},  {"variant", o.variant}, {"linear_solver", o.linear_solver}, {"jacobian", o.jacobian}, {"t_start", o.t_start},
          {"t_end", o.t_end},                 {"step", o.step}, {"step_given", o.step_given}, {"fixed_step", o.fixed_step},       {"output_every", o.output_every},
          {"output_interval", o.output_interval}, {"rtol", o.rtol},   {"atol", o.atol}};
}

RunOptions options_from_json(const json& j) {
  RunOptions o;
  try {
    o.method = method_of(j.at("method").get<std::string>());
    o.variant = j.at("variant").get<std::string>();
    o.linear_solver = j.at("linear_solver").get<std::string>();
    o.jacobian = j.at("jacobian").get<std::string>();
    o.t_start = j.at("t_start").get<double>();
    o.t_end = j.at("t_end").get<double>();
    o.step = j.at("step").get<double>();
    o.step_given = j.at("step_given").get<bool>();
    o.fixed_step = j.at("fixed_step").get<bool>();
    o.output_every = integer(j, "output_every", 1);
    o.output_interval = j.at("output_interval").get<double>();
    o.rtol = j.at("rtol").get<double>();
    o.atol = j.at("atol").get<double>();
  } catch (const json::exception& e) {
    throw InputError(std::string("run options from the coordinator: ") + e.what());
  }
  try {
    check_options(o);  // as a run started here checks them
  } catch (const InputError& e) {
    throw InputError("run options from the coordinator: " + e.text());
  }
  return o;
}

json loose_to_json(const LooseOptions& l) {
  json methods = json::array();
  for (Method m : l.methods) methods.push_back(method_name(m));
  return {{"macro_step", l.macro_step}, {"extrapolation", l.extrapolation}, {"max_lag", l.max_lag},
          {"exact_lag", l.exact_lag},   {"methods", methods},         {"overlap", l.overlap},
          {"coupling_tol", l.coupling_tol}};
}

LooseOptions loose_from_json(const json& j) {
  LooseOptions l;
  try {
    l.macro_step = j.at("macro_step").get<double>();
    l.extrapolation = integer(j, "extrapolation", 0, 2);
    l.max_lag = integer(j, "max_lag", 0, 1000);
    l.exact_lag = j.at("exact_lag").get<bool>();
    l.overlap = j.at("overlap").get<double>();
    l.coupling_tol = j.at("coupling_tol").get<double>();
    for (const std::string& name : j.at("methods").get<std::vector<std::string>>()) l.methods.push_back(method_of(name));
  } catch (const json::exception& e) {
    throw InputError(std::string("loose-coupling options from the coordinator: ") + e.what());
  }
  try {
    check_loose_options(l);
  } catch (const InputError& e) {
    throw InputError("loose-coupling options from the coordinator: " + e.text());
  }
  return l;
}

}  // namespace mbsflow
