#pragma once
// MultibodySystem's rigid and kinematic joints as compiled (multibody_constraints.cpp),
// shared with the analytic Jacobian of the rigid clusters (cluster_jacobian.cpp).
#include <vector>

#include "constraint_rows.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "rigid_cluster.hpp"

namespace mbsflow {

struct MultibodySystem::Constraints {
  std::vector<JointGeometry> geometry;  // per kinematic joint
  std::vector<RigidCluster> clusters;
  std::vector<int> cluster_of_body;     // -1: in no cluster
  std::vector<Eigen::VectorXd> lambda;  // per cluster, the multipliers of the last solve
  std::vector<char> marked;             // scratch of derivatives_of
  std::vector<Vector6d> wrench;         // scratch
  std::vector<BodyMotion> motion;       // scratch, per cluster slot
  std::vector<Eigen::Vector3d> force, torque;  // scratch, per cluster slot
};

}  // namespace mbsflow
