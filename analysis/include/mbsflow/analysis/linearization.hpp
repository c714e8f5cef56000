#pragma once
// A model's motion linearised about a state, in tangent space: each free body has 6
// coordinates x (its translation, and its rotation as a world-frame rotation vector
// through the exponential map, q = exp(phi) q0) and their rates (velocity, angular
// velocity in the world frame). Driven bodies are held on their motion (no coordinates).
//
//   M x'' + D x' + K x = f      (f: force and torque on each body, world frame)
//   C x = 0                     (the rigid joints' rows)
//
// M is the bodies' mass and world-frame inertia; D and K come from the exact Jacobian of
// the equations of motion (gyroscopic terms in D; the constraint forces' stiffness in K:
// a pendulum in maximal coordinates gets all of its stiffness from it), as
// K = -M dA/dx, D = -M dA/dv restricted to the motions the joints allow.
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

struct LinearModel {
  const Model* model = nullptr;  // the system's (it must outlive this)
  std::vector<int> bodies;  // the free bodies (system indices), coordinates 6 k .. 6 k + 5 each
  Eigen::SparseMatrix<double> M, D, K;  // n x n, n = 6 bodies.size()
  Eigen::SparseMatrix<double> C;        // rows x n; no rows without rigid joints
  std::vector<int> constraint_joint;    // per row of C, its joint
  double t = 0.0;
  Eigen::VectorXd state;  // the state linearised about (the system's layout)
  bool at_rest = true;    // the bodies' velocities are zero there
  Eigen::Index size() const { return M.rows(); }
};

// The linearisation of sys about (t, y). Uses the analytic Jacobian where the model has
// one (MultibodySystem::has_analytic_jacobian), else central differences.
// jacobian: where the analytic Jacobian is evaluated, sys.jacobian_pattern() at the first
// call, kept by a caller that linearises again and again (the equilibrium): the pattern
// costs about as much as the Jacobian, and a large model's (600 MB at 100 000 bodies)
// would be allocated and its pages zeroed afresh at every call.
LinearModel linearize(MultibodySystem& sys, double t, const Eigen::VectorXd& y,
                      Eigen::SparseMatrix<double>* jacobian = nullptr);

// The generalised force on each free body at (t, y) with the velocities taken as zero:
// M times the accelerations (force, torque; world frame), the rigid joints' reactions
// included: zero at a static equilibrium.
Eigen::VectorXd static_residual(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const std::vector<int>& bodies);

// The free bodies of sys (not driven), ascending.
std::vector<int> free_bodies(const MultibodySystem& sys);

// The state y moved by the tangent step dx (translation added, rotation exp(dphi) applied
// in the world frame), velocities set to zero.
void apply_tangent_step(const StateLayout& l, const std::vector<int>& bodies, const Eigen::VectorXd& dx, Eigen::VectorXd& y);

}  // namespace mbsflow
