#pragma once
// The flexible bodies' part of the analytic Jacobian (analytic_jacobian.cpp): forward-mode
// dual numbers, as many as the derivatives asked for, through the same equations the
// right-hand side runs (flexible_dynamics.hpp).
#include <Eigen/Core>
#include <vector>

#include "jacobian_seeds.hpp"
#include "mbsflow/graph/flexible_body.hpp"

namespace mbsflow::flexible_jacobian {

using jacobian_seeds::BodyNumbers;

// Node k's 13 numbers (position, quaternion, velocity, body-frame angular velocity, as the
// node follows its frame: flexible_dynamics::node_world) differentiated by the frame's 13
// numbers, eta and eta': 13 x (13 + 2 ne).
Eigen::MatrixXd node_map(const FloatingFrameData& d, int k, const BodyNumbers& frame, const Eigen::VectorXd& eta,
                         const Eigen::VectorXd& eta_rate);

// A world wrench on a slot of the flexible body (its frame, or a node) and its derivatives
// by the variables (6 x variables): force, then torque.
struct SlotWrench {
  Eigen::Matrix<double, 6, 1> value;
  Eigen::MatrixXd derivatives;
};

// The flexible body's rates that depend on the state, differentiated by `variables`
// variables, the first 13 + 2 ne of them the frame's numbers, eta and eta': rows the
// frame's quaternion rate (4), velocity rate (3, world), angular velocity rate (3, body),
// then the modal accelerations (ne). wrench: the frame's (gravity on the part's mass in
// it), then each node's.
Eigen::MatrixXd rate_derivatives(const FlexibleBody& fb, const Eigen::Vector3d& gravity, const BodyNumbers& frame,
                                 const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const std::vector<SlotWrench>& wrench,
                                 int variables);

}  // namespace mbsflow::flexible_jacobian
