// Every method mbsflow integrates with, by name: one line each.
#include "stepper_registry.hpp"

#include <array>

namespace mbsflow {
namespace {

const std::array<StepperEntry, 4> entries{{
    {Method::rk4, "classic Runge-Kutta, fixed step", false, make_rk4_stepper},
    {Method::dopri5, "Dormand-Prince 5(4), error control, dense output", true, make_dopri5_stepper},
    {Method::colloc, "collocation block methods, s/(s+1)-point step control (implicit)", true, make_colloc_stepper},
    {Method::tirk, "triangularised implicit Runge-Kutta, Radau IIA by default (implicit)", true, make_tirk_stepper},
}};

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

std::unique_ptr<Stepper> make_stepper(Method method, const StepperSystem& system, const StepperSettings& settings) {
  const StepperEntry* e = find_stepper(method.name());
  if (!e) throw InputError("unknown method '" + std::string(method.name()) + "' (" + method_list() + ")");
  return e->make(system, settings);
}

}  // namespace mbsflow
