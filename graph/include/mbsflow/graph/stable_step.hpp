#pragma once
// An upper bound of the fastest eigenvalue of the linearised model, from Gershgorin
// discs of the mass-scaled stiffness and damping of every body, and the RK4 step
// that keeps h * lambda inside RK4's stability region.
#include <string>
#include <vector>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

struct StableStep {
  double step = 0.0;          // largest RK4 step with h * lambda_max <= rk4_stability_radius
  double lambda_max = 0.0;    // bound on |eigenvalue|, 1/s
  int body = -1;              // body where the bound is reached
  int joint = -1;             // stiffest joint at that body
  std::string describe(const Model& model) const;
};

// RK4 is stable on the imaginary axis up to 2.83 and on the negative real axis up to
// 2.79; 2.5 leaves a margin for damped eigenvalues between the two.
inline constexpr double rk4_stability_radius = 2.5;

StableStep estimate_stable_step(const Model& model);

// Per joint, the fastest undamped rate (1/s) of its two bodies joined by it alone (a
// driven body or the ground held still): infinity for a rigid joint, 0 for one without
// stiffness. The RK4 stable step of joint j alone is rk4_stability_radius / rate[j].
std::vector<double> joint_rates(const Model& model);

}  // namespace mbsflow
