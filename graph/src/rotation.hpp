#pragma once
// Small quaternion and rotation helpers on Eigen fixed-size vectors.
// Quaternions are (w, x, y, z) in an Eigen::Vector4d and need not be exactly unit:
// every function here gives the rotation of q / |q|.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "lanes.hpp"

namespace mbsflow {

// The helpers are templates on the scalar so that the analytic Jacobian can differentiate
// the same arithmetic (analytic_jacobian.cpp); the double overloads below take Eigen
// expressions (columns of a matrix) as well.
template <class S>
using Vector3T = Eigen::Matrix<S, 3, 1>;
template <class S>
using Vector4T = Eigen::Matrix<S, 4, 1>;
template <class S>
using Matrix3T = Eigen::Matrix<S, 3, 3>;

template <class S>
[[gnu::always_inline]] inline Matrix3T<S> rotation_matrix(const Vector4T<S>& q) {
  const S w = q[0], x = q[1], y = q[2], z = q[3];
  const S s = 2.0 / (w * w + x * x + y * y + z * z);
  const S xs = x * s, ys = y * s, zs = z * s;
  const S wx = w * xs, wy = w * ys, wz = w * zs;
  const S xx = x * xs, xy = x * ys, xz = x * zs;
  const S yy = y * ys, yz = y * zs, zz = z * zs;
  Matrix3T<S> r;
  r << 1.0 - (yy + zz), xy - wz, xz + wy,
       xy + wz, 1.0 - (xx + zz), yz - wx,
       xz - wy, yz + wx, 1.0 - (xx + yy);
  return r;
}
inline Eigen::Matrix3d rotation_matrix(const Eigen::Vector4d& q) { return rotation_matrix<double>(q); }

template <class S>
[[gnu::always_inline]] inline Vector4T<S> quat_multiply(const Vector4T<S>& a, const Vector4T<S>& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}
inline Eigen::Vector4d quat_multiply(const Eigen::Vector4d& a, const Eigen::Vector4d& b) { return quat_multiply<double>(a, b); }

template <class S>
[[gnu::always_inline]] inline Vector4T<S> quat_conjugate(const Vector4T<S>& q) {
  return {q[0], -q[1], -q[2], -q[3]};
}
inline Eigen::Vector4d quat_conjugate(const Eigen::Vector4d& q) { return quat_conjugate<double>(q); }

// The unit quaternion of the rotation vector theta (axis * angle). Below 1e-8 rad the
// series in angle^2 (whose derivative at zero dual numbers can take, unlike the norm's):
// 1 - angle^2 / 8 rounds to cos(angle / 2) there.
template <class S>
Vector4T<S> quat_exp(const Vector3T<S>& theta) {
  using std::cos, std::sin, std::sqrt;
  const S angle2 = theta.squaredNorm();
  S c, s;
  if (angle2 > 1e-16) {
    const S angle = sqrt(angle2);
    c = cos(0.5 * angle);
    s = sin(0.5 * angle) / angle;
  } else {
    c = 1.0 - angle2 / 8.0;
    s = 0.5 - angle2 / 48.0;
  }
  return {c, s * theta[0], s * theta[1], s * theta[2]};
}
inline Eigen::Vector4d quat_exp(const Eigen::Vector3d& theta) { return quat_exp<double>(theta); }

// Logarithm of a rotation: its rotation vector theta (axis * angle, angle in [0, pi]) and
// the coefficient c of the left Jacobian of SO(3),
//   J_l(theta)^-T = I + [theta]/2 + c [theta]^2,  c = 1/angle^2 - cot(angle/2) / (2 angle),
// with cot(angle/2) = w/|v| read off the quaternion, so no sine or cosine is evaluated.
template <class S>
struct RotationLogT {
  Vector3T<S> theta;
  S c;
};
using RotationLog = RotationLogT<double>;

// atan2(s, w) for 0 <= s <= w / 4 (angles below 0.49 rad, the bending of a stiff bushing):
// the series of atan(s / w) through x^29, whose remainder is below 3e-20 of the sum, in a
// tenth of libm's instructions; within 3 ulp of atan2 (tests/graph/test_rotation.cpp).
inline constexpr double atan_series[15] = {1.0,        -1.0 / 3,  1.0 / 5,  -1.0 / 7,  1.0 / 9,
                                           -1.0 / 11,  1.0 / 13,  -1.0 / 15, 1.0 / 17, -1.0 / 19,
                                           1.0 / 21,   -1.0 / 23, 1.0 / 25, -1.0 / 27, 1.0 / 29};
// Estrin's scheme: the terms in pairs, the pairs in fours, ..., so that the chain of
// dependent operations is 5 multiply-adds long rather than Horner's 14 (a Horner loop
// made the rhs slower though it ran fewer instructions than libm).
template <class S>
[[gnu::always_inline]] inline S small_atan2(const S& s, const S& w) {
  const S x = s / w, x2 = x * x, x4 = x2 * x2, x8 = x4 * x4;
  const double* c = atan_series;
  const S q0 = c[0] + c[1] * x2, q1 = c[2] + c[3] * x2, q2 = c[4] + c[5] * x2, q3 = c[6] + c[7] * x2;
  const S q4 = c[8] + c[9] * x2, q5 = c[10] + c[11] * x2, q6 = c[12] + c[13] * x2;
  const S r0 = q0 + q1 * x4, r1 = q2 + q3 * x4, r2 = q4 + q5 * x4, r3 = q6 + c[14] * x4;
  const S p = (r0 + r1 * x8) + (r2 + r3 * x8) * (x8 * x8);
  return x * p;
}

// Written with pick() rather than if, so that it runs on Lanes too (each lane its branch).
template <class S>
[[gnu::always_inline]] inline RotationLogT<S> rotation_log(const Vector4T<S>& q) {
  using std::atan2;  // and Eigen's, for automatic differentiation, by argument-dependent lookup
  using C = LaneConstant<S>;
  const C sign = pick(q[0] < 0.0, [] { return C(-1.0); }, [] { return C(1.0); });  // shortest rotation
  const S w = sign * q[0];
  const Vector3T<S> v = sign * q.template tail<3>();
  const S s = v.norm();  // for dual numbers its derivatives are not finite at 0, but then unused
  const auto tiny = s < 1e-7 * w;  // then angle/s = 2/w (1 - (s/w)^2/3 + ...) to rounding
  const S angle = pick(tiny, [] { return S(0.0); }, [&]() -> S {
    return 2.0 * pick(s <= 0.25 * w, [&]() -> S { return small_atan2<S>(s, w); }, [&]() -> S { return atan2(s, w); });
  });
  RotationLogT<S> r;
  r.theta = pick(tiny, [&]() -> S { return 2.0 / w; }, [&]() -> S { return angle / s; }) * v;
  const S a2 = pick(tiny, [&]() -> S { return r.theta.squaredNorm(); }, [&]() -> S { return angle * angle; });
  const auto series = [&]() -> S {  // error < 1e-16
    return 1.0 / 12.0 + a2 * (1.0 / 720.0 + a2 * (1.0 / 30240.0 + a2 / 1209600.0));
  };
  r.c = pick(tiny, series, [&]() -> S { return pick(a2 >= 1e-2, [&]() -> S { return 1.0 / a2 - w / (2.0 * angle * s); }, series); });
  return r;
}
inline RotationLog rotation_log(const Eigen::Vector4d& q) { return rotation_log<double>(q); }

inline Eigen::Vector3d rotation_vector(const Eigen::Vector4d& q) { return rotation_log(q).theta; }

// J_l(theta)^-T tau: maps the gradient of an energy in rotation-vector coordinates to the
// torque this energy exerts, so that a bushing's rotational spring is exactly
// conservative at any angle below pi.
template <class S>
[[gnu::always_inline]] inline Vector3T<S> rotation_gradient_to_torque(const RotationLogT<S>& r, const Vector3T<S>& tau) {
  const Vector3T<S> txt = r.theta.cross(tau);
  return tau + 0.5 * txt + r.c * r.theta.cross(txt);
}
inline Eigen::Vector3d rotation_gradient_to_torque(const RotationLog& r, const Eigen::Vector3d& tau) {
  return rotation_gradient_to_torque<double>(r, tau);
}

}  // namespace mbsflow
