#pragma once
// The kinematic joints in maximal coordinates: each joint is a few scalar constraint
// equations phi(positions, t) = 0 between the joint frame on body a (body1) and the one
// on body b (body2), built from four basic ones (Haug's): a point offset along an axis of
// frame a, two axes kept perpendicular, a distance, and the angle about the joint axis.
// A row gives what an index-1 solve and a projection need, with V = (v_a, w_a, v_b, w_b)
// and A its time derivative, world frame, angular velocities of the bodies in world frame:
//   phi' = j . V + rate,   phi'' = j . A + bias.
#include <Eigen/Core>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

struct BodyMotion {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();  // centre of mass
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // body to world
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // of the centre of mass
  Eigen::Vector3d w = Eigen::Vector3d::Zero();  // angular velocity, world frame
};

using RowJacobian = Eigen::Matrix<double, 12, 1>;  // v_a, w_a, v_b, w_b

struct ConstraintRow {
  double phi = 0.0;   // violation; 0 for a velocity-level row
  double rate = 0.0;  // phi' - j . V
  double bias = 0.0;  // phi'' - j . A
  RowJacobian j = RowJacobian::Zero();
  int axis = 0;       // the joint-frame direction it holds: 0..2 along x y z, 3..5 about x y z
  bool holonomic = true;
};

// A kinematic joint ready to evaluate: points in each body's frame, frame axes (columns
// x, y, z) in each body's frame, the rod length, the motor and the limits.
struct JointGeometry {
  JointType type = JointType::spherical;
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
  Eigen::Matrix3d fa = Eigen::Matrix3d::Identity(), fb = Eigen::Matrix3d::Identity();
  double length = 0.0;
  JointMotor motor;
  JointLimits limits;
};

JointGeometry joint_geometry(const Joint& joint);

// Rows of the joint's constraint: its own, plus one for a position or velocity motor.
int constraint_rows(const JointGeometry& g);
// Fills rows[0 .. constraint_rows(g)).
void evaluate_constraint(const JointGeometry& g, const BodyMotion& a, const BodyMotion& b, double t, ConstraintRow* rows);

// The joint coordinate along its axis (revolute: angle of frame b about z of frame a, in
// (-pi, pi]; prismatic: displacement of point b along z of frame a) as a row.
ConstraintRow joint_coordinate(const JointGeometry& g, const BodyMotion& a, const BodyMotion& b);

// The generalised force p along a row, as the wrench it puts on each body: force on b,
// torque on a, torque on b (world, about the centres of mass); the force on a is minus
// the force on b for every row here.
inline void add_row_wrench(const ConstraintRow& row, double p, Eigen::Ref<Eigen::Matrix<double, 9, 1>> out) {
  out.segment<3>(0) += p * row.j.segment<3>(6);
  out.segment<3>(3) += p * row.j.segment<3>(3);
  out.segment<3>(6) += p * row.j.segment<3>(9);
}

}  // namespace mbsflow
