#pragma once
// The force laws of the compliant joints (bushings and springs) and of the loads, and the
// rates of a free body, as templates on the scalar: the right-hand side evaluates them in
// double, the analytic Jacobian (analytic_jacobian.cpp) in forward-mode dual numbers, so
// both read one piece of arithmetic.
#include <array>
#include <type_traits>

#include "mbsflow/graph/force_table.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/multibody_system.hpp"  // inertia_matrix
#include "as_eigen.hpp"
#include "rotation.hpp"

namespace mbsflow {

// One body's kinematics at an evaluation, world frame (angular velocity too).
template <class S>
struct BodyFrameT {
  Matrix3T<S> rot;  // body to world
  Vector3T<S> pos, vel, omega;
  Vector4T<S> quat;
};

// The same for the right-hand side in double: references into the evaluation's storage.
struct BodyFrameView {
  using Scalar = double;
  const Eigen::Matrix3d& rot;
  Eigen::Block<const Eigen::Matrix3Xd, 3, 1, true> pos, vel, omega;
  Eigen::Block<const Eigen::Matrix4Xd, 4, 1, true> quat;
};

// From the state's numbers: position, quaternion, velocity, body-frame angular velocity.
template <class S>
BodyFrameT<S> body_frame(const Vector3T<S>& r, const Vector4T<S>& q, const Vector3T<S>& v, const Vector3T<S>& w_body) {
  BodyFrameT<S> b;
  b.rot = rotation_matrix(q);
  b.quat = q;
  b.pos = r;
  b.vel = v;
  b.omega = b.rot * w_body;
  return b;
}

// m in scalar S: m itself when it is already (no copy), else a converted copy.
template <class S, class M>
decltype(auto) as_scalar(const M& m) {
  if constexpr (std::is_same_v<S, typename M::Scalar>)
    return (m);
  else
    return m.template cast<S>().eval();
}

// A table's force at x; for dual numbers, the slope of the segment x lies in carries the
// derivatives (a table is piecewise linear).
template <class S>
S table_force_of(const ForceTable& t, const S& x) {
  if constexpr (std::is_same_v<S, double>) {
    return table_force(t, x);
  } else {
    S f = x;
    f.value() = table_force(t, x.value());
    f.derivatives() = table_slope(t, x.value()) * x.derivatives();
    return f;
  }
}

template <class S>
struct DeflectionT {
  Matrix3T<S> frame;         // world orientation of the joint frame on body1
  Vector3T<S> pb;            // world attachment point on body2
  Vector3T<S> d, d_rate;     // translational deflection and its rate, joint frame
  RotationLogT<S> rotation;  // of the relative orientation, joint frame
  Vector3T<S> omega_rel;     // relative angular velocity, joint frame
};

// Joint: MultibodySystem's compiled joint (a, b, pa, pb, frames, stiffness, damping...).
// Body: BodyFrameT<S> or, in double, BodyFrameView.
template <class S, class Joint, class Body>
[[gnu::always_inline]] inline DeflectionT<S> bushing_deflection(const Joint& j, const Body& a, const Body& b) {
  DeflectionT<S> r;
  r.frame = j.frame1_identity ? a.rot : Matrix3T<S>(a.rot * as_scalar<S>(j.rfa));
  const Vector3T<S> bw = b.rot * as_scalar<S>(j.pb);
  r.pb = b.pos + bw;
  const Vector3T<S> pa = a.pos + a.rot * as_scalar<S>(j.pa);
  // Rate of the deflection seen from body1: velocity of the point on body2 minus the
  // velocity of body1's material point that coincides with it.
  const Vector3T<S> dv = b.vel + b.omega.cross(bw) - a.vel - a.omega.cross(r.pb - a.pos);
  r.d = r.frame.transpose() * (r.pb - pa);
  r.d_rate = r.frame.transpose() * dv;
  Vector4T<S> qa = a.quat, qb = b.quat;
  if (!j.frame1_identity) qa = quat_multiply<S>(qa, as_scalar<S>(j.qfa));
  if (!j.frame2_identity) qb = quat_multiply<S>(qb, as_scalar<S>(j.qfb));
  r.rotation = rotation_log<S>(quat_multiply<S>(quat_conjugate<S>(qa), qb));
  r.omega_rel = r.frame.transpose() * (b.omega - a.omega);
  return r;
}

// A bushing's parameters in scalar S, as compliant_joint_wrench reads them: the lane
// kernels (lane_kernels.cpp) fill one with several joints side by side; tests build them
// in double. (MultibodySystem's compiled joint has the same fields, in double.)
template <class S>
struct BushingParams {
  bool spring = false, frame1_identity = true, frame2_identity = true;
  Matrix3T<S> rfa;
  Vector3T<S> pa, pb, kt, ct, kr, cr, preload_force, preload_torque;
  Vector4T<S> qfa, qfb;
  S rest_length = S(0.0);  // read by springs only
};

// Spring forces per axis (K d, or the tables), for axes first_axis..first_axis+2.
template <class S, class Joint>
[[gnu::always_inline]] inline Vector3T<S> axis_forces(const Joint& j, const std::array<ForceTable, 6>* tables, const Vector3T<S>& d, int first_axis) {
  const auto& k = first_axis == 0 ? j.kt : j.kr;
  Vector3T<S> f = as_scalar<S>(k).cwiseProduct(d);
  if constexpr (!is_lanes_v<S>) {  // the lane kernels take no joint with tables
    if (tables)
      for (int i = 0; i < 3; ++i) {
        const ForceTable& table = (*tables)[static_cast<std::size_t>(first_axis + i)];
        if (!table.empty()) f[i] = table_force_of<S>(table, d[i]);
      }
  }
  return f;
}

// What a spring or bushing exerts, into out (9 rows): the force on body2 (rows 0-2; body1
// gets its opposite), the torque on body1 (3-5) and on body2 (6-8), world frame, about the
// centres of mass. On Lanes, bushings only (lane_kernels.cpp).
template <class S, class Joint, class Body, class Out>
[[gnu::always_inline]] inline void compliant_joint_wrench(const Joint& j, const std::array<ForceTable, 6>* tables, const Body& a,
                                                          const Body& b, Out&& out) {
  if constexpr (!is_lanes_v<S>) {
    if (j.spring) {
      const Vector3T<S> aw = a.rot * as_scalar<S>(j.pa), bw = b.rot * as_scalar<S>(j.pb);
      const Vector3T<S> delta = b.pos + bw - a.pos - aw;
      const S length = delta.norm();
      const Vector3T<S> u = length > 0.0 ? Vector3T<S>(delta / length) : Vector3T<S>(Vector3T<S>::Zero());
      const Vector3T<S> dv = b.vel + b.omega.cross(bw) - a.vel - a.omega.cross(aw);
      const S f = j.kt[0] * (length - j.rest_length) + j.ct[0] * u.dot(dv);
      const Vector3T<S> force = -f * u;  // on body2, at its attachment point
      out.template segment<3>(0) = force;
      out.template segment<3>(3) = aw.cross(-force);
      out.template segment<3>(6) = bw.cross(force);
      return;
    }
  }
  const DeflectionT<S> def = bushing_deflection<S>(j, a, b);
  const Vector3T<S> f = axis_forces<S>(j, tables, def.d, 0) + as_scalar<S>(j.ct).cwiseProduct(def.d_rate) - as_scalar<S>(j.preload_force);
  const Vector3T<S> force = -(def.frame * f);  // on body2 at pb; on body1 (opposite) also at pb
  const Vector3T<S>& theta = def.rotation.theta;
  const Vector3T<S> g = rotation_gradient_to_torque<S>(def.rotation, axis_forces<S>(j, tables, theta, 3) - as_scalar<S>(j.preload_torque)) +
                        as_scalar<S>(j.cr).cwiseProduct(def.omega_rel);
  const Vector3T<S> couple = def.frame * g;  // on body1; body2 gets -couple
  out.template segment<3>(0) = force;
  out.template segment<3>(3) = (def.pb - a.pos).cross(-force) + couple;
  out.template segment<3>(6) = (def.pb - b.pos).cross(force) - couple;
}

// Adds a load's force and its torque about the centre of mass, scaled by s (its time
// function's value); r: the body's orientation, v and w its velocity (world) and angular
// velocity (body frame), which a damping load opposes.
template <class S>
[[gnu::always_inline]] inline void add_load(const Load& l, double s, const Matrix3T<S>& r, const Vector3T<S>& v,
                                            const Vector3T<S>& w, Vector3T<S>& force, Vector3T<S>& torque) {
  const Eigen::Vector3d f0 = s * vec(l.force);
  const Eigen::Vector3d m0 = s * vec(l.torque);
  Vector3T<S> f = as_scalar<S>(f0), m = as_scalar<S>(m0);
  if (l.body_frame) {
    f = r * f;
    m = r * m;
  }
  force += f;
  torque += m + (r * as_scalar<S>(vec(l.point))).cross(f);
  if (l.damped()) {
    const Eigen::Matrix3d angular = inertia_matrix(l.angular_damping);
    force -= as_scalar<S>(vec(l.damping)).cwiseProduct(v);
    torque -= r * (as_scalar<S>(angular) * w);
  }
}

// A free body's angular acceleration (body frame) from the world torque on it:
// J w' = R^T T - w x J w.
// (inertia and inv_inertia: 3 x 3, in double or in S.)
template <class S, class Inertia>
[[gnu::always_inline]] inline Vector3T<S> angular_acceleration(const Matrix3T<S>& rot, const Vector3T<S>& w, const Vector3T<S>& torque,
                                 const Inertia& inertia, const Inertia& inv_inertia) {
  const Vector3T<S> tb = rot.transpose() * torque;
  return as_scalar<S>(inv_inertia) * (tb - w.cross(as_scalar<S>(inertia) * w));
}

// q' = q (x) (0, w) / 2, w in the body frame.
template <class S>
[[gnu::always_inline]] inline Vector4T<S> quaternion_rate(const Vector4T<S>& q, const Vector3T<S>& w) {
  return 0.5 * quat_multiply<S>(q, Vector4T<S>(S(0.0), w[0], w[1], w[2]));
}

}  // namespace mbsflow
