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

// Rotation vector (axis * angle, angle in [0, pi]) of the rotation q: the logarithm map.
inline Eigen::Vector3d rotation_vector(const Eigen::Vector4d& q) {
  const double sign = q[0] < 0.0 ? -1.0 : 1.0;  // shortest rotation
  const double w = sign * q[0];
  const Eigen::Vector3d v = sign * q.tail<3>();
  const double s = v.norm();
  if (s < 1e-7 * w) return (2.0 / w) * v;  // angle/s = 2/w (1 - (s/w)^2/3 + ...)
  return (2.0 * std::atan2(s, w) / s) * v;
}

// J_l(theta)^-T tau, with J_l the left Jacobian of SO(3): maps the gradient of an
// energy in rotation-vector coordinates to the torque that this energy exerts,
// so that a bushing's rotational spring is exactly conservative at any angle < pi.
inline Eigen::Vector3d rotation_gradient_to_torque(const Eigen::Vector3d& theta, const Eigen::Vector3d& tau) {
  const double a2 = theta.squaredNorm();
  double c;
  if (a2 < 1e-4) {
    c = 1.0 / 12.0 + a2 * (1.0 / 720.0 + a2 / 30240.0);
  } else {
    const double a = std::sqrt(a2);
    c = 1.0 / a2 - (1.0 + std::cos(a)) / (2.0 * a * std::sin(a));
  }
  const Eigen::Vector3d txt = theta.cross(tau);
  return tau + 0.5 * txt + c * theta.cross(txt);
}

}  // namespace mbsflow
