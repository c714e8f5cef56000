#include "options_json.hpp"

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;

Method method_of(const std::string& name) {
  const std::optional<Method> m = find_method(name);
  if (!m) throw InputError("the coordinator asked for an unknown method " + name);
  return *m;
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
    o.output_every = j.at("output_every").get<int>();
    o.output_interval = j.at("output_interval").get<double>();
    o.rtol = j.at("rtol").get<double>();
    o.atol = j.at("atol").get<double>();
  } catch (const json::exception& e) {
    throw InputError(std::string("run options from the coordinator: ") + e.what());
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
    l.extrapolation = j.at("extrapolation").get<int>();
    l.max_lag = j.at("max_lag").get<int>();
    l.exact_lag = j.at("exact_lag").get<bool>();
    l.overlap = j.at("overlap").get<double>();
    l.coupling_tol = j.at("coupling_tol").get<double>();
    for (const std::string& name : j.at("methods").get<std::vector<std::string>>()) l.methods.push_back(method_of(name));
  } catch (const json::exception& e) {
    throw InputError(std::string("loose-coupling options from the coordinator: ") + e.what());
  }
  return l;
}

}  // namespace mbsflow
