#pragma once
// A model's motion linearised about a state, in tangent space: each free body has 6
// coordinates x (its translation, and its rotation as a world-frame rotation vector
// through the exponential map, q = exp(phi) q0) and their rates (velocity, angular
// velocity in the world frame); a flexible body's frame has its ne modal coordinates
// after its 6. Driven bodies are held on their motion, a flexible body's node bodies
// follow its frame and modes (no coordinates of their own: body_motion gives their motion).
//
//   M x'' + D x' + K x = f      (f: force and torque on each body, world frame; modal forces)
//   C x = 0                     (the rigid joints' rows)
//
// M is the bodies' mass and world-frame inertia (a flexible body's whole mass matrix,
// frame and modes coupled); D and K come from the exact Jacobian of the equations of
// motion (gyroscopic terms in D; the constraint forces' stiffness in K: a pendulum in
// maximal coordinates gets all of its stiffness from it), as K = -M dA/dx, D = -M dA/dv
// restricted to the motions the joints allow.
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

// Which bodies have coordinates, and where they sit.
struct FreeCoordinates {
  std::vector<int> bodies;          // the free bodies (system indices), ascending
  std::vector<Eigen::Index> start;  // per free body its first coordinate; then their count
  // Without flexible bodies: empty. Else per free body the flexible body whose frame it is
  // (-1: none), and per flexible body of the model where its modal coordinates start in
  // the state.
  std::vector<int> flexible;
  std::vector<Eigen::Index> eta;
  Eigen::Index size() const { return start.back(); }
  Eigen::Index count(std::size_t k) const { return start[k + 1] - start[k]; }  // free body k's coordinates
  Eigen::Index modes(std::size_t k) const { return count(k) - 6; }            // of them modal (a frame's)
  int flexible_of(std::size_t k) const { return flexible.empty() ? -1 : flexible[k]; }
  // The free body whose coordinates hold coordinate i.
  std::size_t body_of(Eigen::Index i) const;
  // Per system body (of system_bodies) its index in `bodies`, -1 where it is held.
  std::vector<int> free_index(std::size_t system_bodies) const;
};

struct LinearModel {
  const Model* model = nullptr;  // the system's (it must outlive this)
  FreeCoordinates coords;
  Eigen::SparseMatrix<double> M, D, K;  // n x n, n = coords.size()
  Eigen::SparseMatrix<double> C;        // rows x n; no rows without rigid joints
  std::vector<int> constraint_joint;    // per row of C, its joint
  std::vector<Eigen::Index> constraint_row;  // per row of C, its row of MultibodySystem::constraint_jacobian
  double t = 0.0;
  Eigen::VectorXd state;  // the state linearised about (the system's layout)
  bool at_rest = true;    // the bodies' velocities are zero there
  Eigen::Index size() const { return M.rows(); }
};

// The linearisation of sys about (t, y). Uses the analytic Jacobian where the model has
// one (MultibodySystem::has_analytic_jacobian), else central differences.
// jacobian: where the analytic Jacobian is evaluated, kept by a caller that linearises
// again and again (the equilibrium, then the modes at its end); an empty matrix gets
// sys.jacobian_pattern(). The pattern and its first fill cost about as much as an
// iteration, and a large model's (600 MB at 100 000 bodies) would be allocated and its
// pages zeroed afresh at every call.
// with_damping = false: D is left empty (n x n, no entries), for a caller that needs M and
// K only (the equilibrium's steps).
LinearModel linearize(MultibodySystem& sys, double t, const Eigen::VectorXd& y,
                      Eigen::SparseMatrix<double>* jacobian = nullptr, bool with_damping = true);
// The same into out, whose matrices' storage is reused where the sizes allow: for a caller
// that linearises again and again (Eigen 3.4's SparseMatrix has no move constructor, so a
// returned LinearModel moved into place is copied, K alone 130 MB at 100 000 bodies).
void linearize_into(LinearModel& out, MultibodySystem& sys, double t, const Eigen::VectorXd& y,
                    Eigen::SparseMatrix<double>* jacobian = nullptr, bool with_damping = true);

// The generalised force on each free body at (t, y) with the velocities taken as zero:
// M times the accelerations (force, torque; world frame; the modal forces), the rigid
// joints' reactions included: zero at a static equilibrium.
Eigen::VectorXd static_residual(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const FreeCoordinates& c);

// The free bodies of sys (not driven, not a flexible body's node) and their coordinates.
FreeCoordinates free_coordinates(const MultibodySystem& sys);

// y with every velocity and modal rate zero.
void set_at_rest(const StateLayout& l, const FreeCoordinates& c, Eigen::VectorXd& y);

// The state y moved by the tangent step dx (translation added, rotation exp(dphi) applied
// in the world frame, modal coordinates added), velocities set to zero.
void apply_tangent_step(const StateLayout& l, const FreeCoordinates& c, const Eigen::VectorXd& dx, Eigen::VectorXd& y);

// The small motion of every body of the model (6 rows each: translation, rotation; world
// frame) from the coordinates: a free body's own, a flexible body's node through its
// frame's and the modes', zero for a driven body. (6 bodies) x n.
Eigen::SparseMatrix<double> body_motion(const LinearModel& lm);

}  // namespace mbsflow
