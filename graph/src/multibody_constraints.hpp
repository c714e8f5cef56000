#pragma once
// MultibodySystem's rigid and kinematic joints as compiled (multibody_constraints.cpp),
// shared with the analytic Jacobian of the rigid clusters (cluster_jacobian.cpp).
#include <vector>

#include "constraint_rows.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "rigid_cluster.hpp"

namespace mbsflow {

inline constexpr double projection_tolerance = 1e-10;  // largest |phi| a projection leaves (m, or rad)
inline constexpr int projection_iterations = 6;        // Newton iterations of a projection at most

// How the body slots of a cluster that holds flexible bodies map onto its generalised
// velocities: each rigid body's (v, w) in world axes, each flexible body's [v_b, w, eta']
// (flexible_body.hpp) once for its frame and all its nodes (flexible_joints.cpp).
struct FlexibleSlots {
  std::vector<int> flexible;       // the model's flexible bodies in the cluster
  std::vector<int> owner;          // per slot: its index in `flexible`, -1 for a rigid body
  std::vector<int> node;           // per slot of a flexible body: its node, -1 for the frame
  std::vector<Eigen::Index> start; // per slot: its first generalised velocity (a flexible body's block)
  std::vector<Eigen::Index> block; // per flexible body: its block's first generalised velocity
  Eigen::Index size = 0;
};

// A body's motion read from the state (ground, past the bodies, stays at rest).
BodyMotion state_motion(const StateLayout& l, const Eigen::VectorXd& y, Eigen::Index i);

struct MultibodySystem::Constraints {
  std::vector<JointGeometry> geometry;  // per kinematic joint
  std::vector<RigidCluster> clusters;
  std::vector<int> cluster_of_body;     // -1: in no cluster
  std::vector<Eigen::VectorXd> lambda;  // per cluster, the multipliers of the last solve
  // The clusters that hold flexible bodies: per cluster its index into `flexible`, or -1
  // (empty in a model without flexible bodies).
  std::vector<int> flexible_of_cluster;
  std::vector<FlexibleSlots> flexible;
  const FlexibleSlots* flexible_slots_of(int c) const {
    if (flexible_of_cluster.empty() || flexible_of_cluster[static_cast<std::size_t>(c)] < 0) return nullptr;
    return &flexible[static_cast<std::size_t>(flexible_of_cluster[static_cast<std::size_t>(c)])];
  }
  std::vector<char> marked;             // scratch of derivatives_of
  std::vector<Vector6d> wrench;         // scratch
  std::vector<BodyMotion> motion;       // scratch, per cluster slot
  std::vector<Eigen::Vector3d> force, torque;  // scratch, per cluster slot
};

}  // namespace mbsflow
