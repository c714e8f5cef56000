#pragma once
// Helpers shared by the tests: single bodies and joints, fixed-step integration.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "convergence.hpp"

namespace mbsflow::test {

inline Body make_body(const char* name, double mass, Vec6 inertia, Vec3 position = {}) {
  Body b;
  b.name = name;
  b.mass = mass;
  b.inertia = inertia;
  b.position = position;
  return b;
}

inline Joint make_bushing(int body1, int body2, Vec3 p1, Vec3 p2, Vec6 k, Vec6 c = {}) {
  Joint j;
  j.name = "j" + std::to_string(body2);
  j.body1 = body1;
  j.body2 = body2;
  j.point1 = p1;
  j.point2 = p2;
  j.stiffness = k;
  j.damping = c;
  return j;
}

// Integrates with RK4 and the mechanics' after-step projection; calls f(t, y) after each step.
template <class F>
Eigen::VectorXd integrate_rk4(MultibodySystem& sys, double t_end, long steps, F f) {
  Eigen::VectorXd y = sys.initial_state();
  Rk4 rk(sys.dimension());
  const double h = t_end / static_cast<double>(steps);
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * h;
    rk.step(sys, t, h, y);
    sys.after_step(t + h, y);
    f(t + h, y);
  }
  return y;
}

inline Eigen::VectorXd integrate_rk4(MultibodySystem& sys, double t_end, long steps) {
  return integrate_rk4(sys, t_end, steps, [](double, const Eigen::VectorXd&) {});
}

}  // namespace mbsflow::test
