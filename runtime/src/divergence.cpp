#include "mbsflow/runtime/divergence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

std::optional<Divergence> find_divergence(const StateLayout& layout, const Eigen::VectorXd& y, Eigen::Index bodies) {
  const Eigen::Index n = bodies < 0 ? layout.bodies : bodies;
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool finite = y.segment<3>(layout.position(i)).allFinite() && y.segment<4>(layout.orientation(i)).allFinite() &&
                        y.segment<3>(layout.velocity(i)).allFinite() &&
                        y.segment<3>(layout.angular_velocity(i)).allFinite();
    if (!finite) return Divergence{static_cast<int>(i), "state is not finite"};
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double v = y.segment<3>(layout.velocity(i)).norm();
    const double w = y.segment<3>(layout.angular_velocity(i)).norm();
    char buf[96];
    if (v > divergence_speed) {
      std::snprintf(buf, sizeof buf, "speed %.3g m/s", v);
      return Divergence{static_cast<int>(i), buf};
    }
    if (w > divergence_angular_speed) {
      std::snprintf(buf, sizeof buf, "angular speed %.3g rad/s", w);
      return Divergence{static_cast<int>(i), buf};
    }
  }
  return std::nullopt;
}

std::string describe_unknown(const Model& model, Eigen::Index i) {
  const auto n = static_cast<Eigen::Index>(model.bodies.size());
  if (i < 0 || i >= StateLayout{n}.size()) return "unknown " + std::to_string(i);
  static const char* const fields[] = {"position", "orientation", "velocity", "angular velocity"};
  const StateLayout l{n};
  const Eigen::Index starts[] = {l.position(0), l.orientation(0), l.velocity(0), l.angular_velocity(0), l.size()};
  int f = 0;
  while (i >= starts[f + 1]) ++f;
  const int width = f == 1 ? 4 : 3;
  const auto body = static_cast<int>((i - starts[f]) / width);
  const auto component = static_cast<int>((i - starts[f]) % width);
  static const char* const xyz[] = {"x", "y", "z"}, *const wxyz[] = {"w", "x", "y", "z"};
  std::string out = std::string("the ") + fields[f] + " (" + (f == 1 ? wxyz : xyz)[component] + ") of body '" +
                    model.bodies[static_cast<std::size_t>(body)].name + "'";
  std::vector<const Joint*> at;
  for (const Joint& j : model.joints)
    if (j.body1 == body || j.body2 == body) at.push_back(&j);
  if (at.empty()) return out;
  auto stiffest = [](const Joint* j) { return *std::max_element(j->stiffness.begin(), j->stiffness.end()); };
  std::stable_sort(at.begin(), at.end(), [&](const Joint* a, const Joint* b) { return stiffest(a) > stiffest(b); });
  out += at.size() == 1 ? " (joint" : " (joints, stiffest first,";
  for (std::size_t k = 0; k < at.size() && k < 4; ++k) out += (k ? ", '" : " '") + at[k]->name + "'";
  if (at.size() > 4) out += ", ...";
  return out + ")";
}

std::string divergence_message(const Model& model, const Divergence& d, double t, Method method, double step) {
  const StableStep s = estimate_stable_step(model);
  char buf[512];
  const char* body = model.bodies.at(static_cast<std::size_t>(d.body)).name.c_str();
  if (!stepper_entry(method).adaptive) {
    const double suggest = step > s.step ? s.step : 0.5 * step;
    std::snprintf(buf, sizeof buf,
                  "run diverged at t = %.6g s: body '%s': %s. The %s step %.3g s %s the estimated stability limit %s; "
                  "try {step=%.3g} (or {method=dopri5})",
                  t, body, d.what.c_str(), method.name(), step, step > s.step ? "exceeds" : "is within", s.describe(model).c_str(),
                  suggest);
  } else {
    std::snprintf(buf, sizeof buf,
                  "run diverged at t = %.6g s: body '%s': %s. Try tighter tolerances ({rtol}) or {method=rk4} "
                  "with {step=%.3g} (estimated stability limit %s)",
                  t, body, d.what.c_str(), 0.5 * s.step, s.describe(model).c_str());
  }
  return buf;
}

std::string loose_divergence_message(const Model& model, const Divergence& d, double t, Method method, double step,
                                     double macro_step, int lag, double overlap) {
  const StableStep s = estimate_stable_step(model);
  if (!stepper_entry(method).adaptive && step > s.step) return divergence_message(model, d, t, method, step);
  char advice[160];
  if (lag > 0)
    std::snprintf(advice, sizeof advice, "{max_lag=0} (then each submodel integrates its neighbours' bodies near the cut)");
  else if (overlap < macro_step)
    std::snprintf(advice, sizeof advice, "{overlap=%.3g} (each submodel integrates its neighbours' bodies near the cut)",
                  macro_step);
  else
    std::snprintf(advice, sizeof advice, "{overlap=%.3g}", 2.0 * overlap);
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "run diverged at t = %.6g s: body '%s': %s. Loosely coupled with a macro step of %.3g s, an overlap of "
                "%.3g s and neighbour values up to %d macro steps old: extrapolated neighbours of stiff joints (estimated "
                "stability limit %s) make the coupling unstable unless the overlap covers a macro step; try %s",
                t, model.bodies.at(static_cast<std::size_t>(d.body)).name.c_str(), d.what.c_str(), macro_step, overlap,
                lag + 1, s.describe(model).c_str(), advice);
  return buf;
}

}  // namespace mbsflow
