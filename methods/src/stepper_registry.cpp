// Every method mbsflow integrates with, by name: one line each.
#include "stepper_registry.hpp"

#include <string>
#include <vector>

namespace mbsflow {
namespace {

// name, summary, adaptive, implicit, tight_stages, factory
const StepperEntry entries[] = {
    {Method::rk4, "classic Runge-Kutta, fixed step", false, false, 4, make_rk4_stepper},
    {Method::dopri5, "Dormand-Prince 5(4), error control, dense output", true, false, 7, make_dopri5_stepper},
    {Method::colloc, "collocation block methods, s/(s+1)-point step control (implicit)", true, true, 0, make_colloc_stepper},
    {Method::tirk, "triangularised implicit Runge-Kutta, Radau IIA by default (implicit)", true, true, 0, make_tirk_stepper},
};

}  // namespace

std::span<const StepperEntry> stepper_entries() { return entries; }

const StepperEntry* find_stepper(std::string_view name) {
  for (const StepperEntry& e : entries)
    if (name == e.method.name()) return &e;
  return nullptr;
}

std::optional<Method> find_method(std::string_view name) {
  if (const StepperEntry* e = find_stepper(name)) return e->method;
  return std::nullopt;
}

std::string method_list() {
  std::string out;
  for (const StepperEntry& e : entries) out += (out.empty() ? "" : ", ") + std::string(e.method.name());
  return out;
}

std::string method_names(bool (*keep)(const StepperEntry&), const char* conjunction, std::string (*spell)(const char*)) {
  std::vector<std::string> names;
  for (const StepperEntry& e : entries)
    if (keep(e)) names.push_back(spell ? spell(e.method.name()) : std::string(e.method.name()));
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += std::string(i == 0 ? "" : i + 1 == names.size() ? std::string(" ") + conjunction + " " : ", ") + names[i];
  return out;
}

const StepperEntry& stepper_entry(Method method) {
  if (const StepperEntry* e = find_stepper(method.name())) return *e;
  throw InputError("unknown method '" + std::string(method.name()) + "' (" + method_list() + ")");
}

std::unique_ptr<Stepper> make_stepper(Method method, const StepperSystem& system, const StepperSettings& settings) {
  return stepper_entry(method).make(system, settings);
}

}  // namespace mbsflow
