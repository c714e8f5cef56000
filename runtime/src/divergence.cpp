#include "mbsflow/runtime/divergence.hpp"

#include <cmath>
#include <cstdio>

#include "mbsflow/graph/stable_step.hpp"

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

std::string divergence_message(const Model& model, const Divergence& d, double t, Method method, double step) {
  const StableStep s = estimate_stable_step(model);
  char buf[512];
  const char* body = model.bodies.at(static_cast<std::size_t>(d.body)).name.c_str();
  if (method == Method::rk4) {
    const double suggest = step > s.step ? s.step : 0.5 * step;
    std::snprintf(buf, sizeof buf,
                  "run diverged at t = %.6g s: body '%s': %s. The RK4 step %.3g s %s the estimated stability limit %s; "
                  "try {step=%.3g} (or {method=dopri5})",
                  t, body, d.what.c_str(), step, step > s.step ? "exceeds" : "is within", s.describe(model).c_str(),
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
                                     double macro_step, int lag) {
  const StableStep s = estimate_stable_step(model);
  if (method == Method::rk4 && step > s.step) return divergence_message(model, d, t, method, step);
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "run diverged at t = %.6g s: body '%s': %s. Loosely coupled with a macro step of %.3g s and neighbour "
                "values up to %d macro steps old: explicit coupling of stiff joints needs a macro step well inside their "
                "period (estimated stability limit %s); try {macro_step=%.3g} or a smaller {max_lag}",
                t, model.bodies.at(static_cast<std::size_t>(d.body)).name.c_str(), d.what.c_str(), macro_step, lag + 1,
                s.describe(model).c_str(), 0.5 * macro_step);
  return buf;
}


}  // namespace mbsflow
