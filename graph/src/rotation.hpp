#pragma once
// Small quaternion and rotation helpers on Eigen fixed-size vectors.
// Quaternions are (w, x, y, z) in an Eigen::Vector4d and need not be exactly unit:
// every function here gives the rotation of q / |q|.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace mbsflow {

inline Eigen::Matrix3d rotation_matrix(const Eigen::Vector4d& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double s = 2.0 / (w * w + x * x + y * y + z * z);
  const double xs = x * s, ys = y * s, zs = z * s;
  const double wx = w * xs, wy = w * ys, wz = w * zs;
  const double xx = x * xs, xy = x * ys, xz = x * zs;
  const double yy = y * ys, yz = y * zs, zz = z * zs;
  Eigen::Matrix3d r;
  r << 1.0 - (yy + zz), xy - wz, xz + wy,
       xy + wz, 1.0 - (xx + zz), yz - wx,
       xz - wy, yz + wx, 1.0 - (xx + yy);
  return r;
}

inline Eigen::Vector4d quat_multiply(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

inline Eigen::Vector4d quat_conjugate(const Eigen::Vector4d& q) { return {q[0], -q[1], -q[2], -q[3]}; }

// Logarithm of a rotation: its rotation vector theta (axis * angle, angle in [0, pi]) and
// the coefficient c of the left Jacobian of SO(3),
//   J_l(theta)^-T = I + [theta]/2 + c [theta]^2,  c = 1/angle^2 - cot(angle/2) / (2 angle),
// with cot(angle/2) = w/|v| read off the quaternion, so no sine or cosine is evaluated.
struct RotationLog {
  Eigen::Vector3d theta;
  double c;
};

inline RotationLog rotation_log(const Eigen::Vector4d& q) {
  const double sign = q[0] < 0.0 ? -1.0 : 1.0;  // shortest rotation
  const double w = sign * q[0];
  const Eigen::Vector3d v = sign * q.tail<3>();
  const double s = v.norm();
  RotationLog r;
  double a2;
  if (s < 1e-7 * w) {  // angle/s = 2/w (1 - (s/w)^2/3 + ...)
    r.theta = (2.0 / w) * v;
    a2 = r.theta.squaredNorm();
  } else {
    const double angle = 2.0 * std::atan2(s, w);
    r.theta = (angle / s) * v;
    a2 = angle * angle;
    if (a2 >= 1e-2) {
      r.c = 1.0 / a2 - w / (2.0 * angle * s);
      return r;
    }
  }
  r.c = 1.0 / 12.0 + a2 * (1.0 / 720.0 + a2 * (1.0 / 30240.0 + a2 / 1209600.0));  // series, error < 1e-16
  return r;
}

inline Eigen::Vector3d rotation_vector(const Eigen::Vector4d& q) { return rotation_log(q).theta; }

// J_l(theta)^-T tau: maps the gradient of an energy in rotation-vector coordinates to the
// torque this energy exerts, so that a bushing's rotational spring is exactly
// conservative at any angle below pi.
inline Eigen::Vector3d rotation_gradient_to_torque(const RotationLog& r, const Eigen::Vector3d& tau) {
  const Eigen::Vector3d txt = r.theta.cross(tau);
  return tau + 0.5 * txt + r.c * r.theta.cross(txt);
}

}  // namespace mbsflow
