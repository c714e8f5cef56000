#pragma once
// The checks every implicit integrator makes of its problem and of the settings they share
// (tolerances, step factors, steps, threads); throws InputError.
#include "mbsflow/error.hpp"
#include <string>
#include <utility>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

template <class Settings>
void check_common_settings(const OdeProblem& p, const Settings& s) {
  auto bad = [](const std::string& what) { throw InputError(what); };
  if (p.size < 1 || p.y0.size() != p.size || !p.rhs) bad("the problem needs a size, y0 of that size and a right-hand side");
  if (!(p.t_end > p.t0)) bad("the end time must be after the start time");
  if (!(s.rtol > 0) || !(s.atol > 0)) bad("tolerances must be positive");
  for (const auto& [name, v] : {std::pair{"rtol", &s.rtols}, std::pair{"atol", &s.atols}}) {
    if (v->size() == 0) continue;
    if (v->size() != p.size)
      bad(std::string("per-component ") + name + " needs one value per equation (" + std::to_string(v->size()) + " given for " +
          std::to_string(p.size) + ")");
    if (!(v->array() > 0).all() || !v->allFinite()) bad("tolerances must be positive");
  }
  if (!(s.facmin > 0 && s.facmin < 1 && s.facmax > 1)) bad("facmin must be in (0, 1) and facmax above 1");
  if (s.fixed_step < 0 || s.initial_step < 0) bad("steps must be positive");
  if (s.threads < 0) bad("threads must be >= 0");
}

}  // namespace mbsflow
