#pragma once
// Static equilibrium of a model: the positions where every free body's force and torque
// balance with the velocities zero, the rigid joints held and the quaternions unit.
// Newton on the force balance in tangent space, globalised by pseudo-transient
// continuation: each step solves (K + M / h^2) dx = F on the joints' allowed motions
// (augmented with their rows), and h grows as the residual falls, so that far from
// equilibrium a step follows the forces like a damped motion (a pendulum released level,
// a chain hanging down) and near it the step is Newton's; h shrinks where the potential
// fell far less than the step's quadratic model said. A step that raises the potential
// energy (gravity and elastic) is taken again with a smaller h.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

struct EquilibriumOptions {
  int max_iterations = 500;
  double tolerance = 1e-9;  // the residual force, relative to the bodies' weight and the initial residual
  // Told after each iteration (iteration, residual norm); may be empty.
  std::function<void(int, double)> progress;
};

struct Equilibrium {
  Eigen::VectorXd state;  // the system's layout, velocities zero
  int iterations = 0;
  double residual = 0.0;  // largest force (N) or torque (N m) left on a free body
  double initial_residual = 0.0;
  // The right-hand side's Jacobian as the iterations last filled it (empty where the model
  // has no analytic one): for linearize() at the equilibrium, which then fills it in place.
  // A fresh pattern and its first fill cost about an iteration (1.3 s at 100 000 bodies).
  Eigen::SparseMatrix<double> jacobian;
};

// RunError naming the body that will not settle, and its residual force, when the
// iterations run out.
Equilibrium find_equilibrium(MultibodySystem& sys, double t, const Eigen::VectorXd& start,
                             const EquilibriumOptions& options = {});

}  // namespace mbsflow
