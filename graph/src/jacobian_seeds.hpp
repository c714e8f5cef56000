#pragma once
// The dual numbers of the analytic Jacobian (analytic_jacobian.cpp, cluster_jacobian.cpp):
// a body's 13 state numbers seeded as variables, and the views of them that the force
// laws and the constraint rows take.
#include <Eigen/Core>
#include <unsupported/Eigen/AutoDiff>

#include "constraint_rows.hpp"
#include "force_laws.hpp"
#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow::jacobian_seeds {

constexpr int body_states = 13;  // position 3, quaternion 4, velocity 3, angular velocity 3
// A joint's wrench (or constraint rows) depends on the states of its two bodies, a body's
// own rates on its own.
using Dual = Eigen::AutoDiffScalar<Eigen::Matrix<double, 2 * body_states, 1>>;
using BodyDual = Eigen::AutoDiffScalar<Eigen::Matrix<double, body_states, 1>>;
using Block6 = Eigen::Matrix<double, 6, body_states>;

// A body's 13 state numbers in the variables' order: position, quaternion, velocity,
// body-frame angular velocity.
using BodyNumbers = Eigen::Matrix<double, body_states, 1>;
inline BodyNumbers body_numbers(const Eigen::VectorXd& y, const StateLayout& l, Eigen::Index i) {
  BodyNumbers s;
  s << y.segment<3>(l.position(i)), y.segment<4>(l.orientation(i)), y.segment<3>(l.velocity(i)), y.segment<3>(l.angular_velocity(i));
  return s;
}

// A body's state numbers s as the variables first..first+12.
template <class D>
struct SeededState {
  Vector3T<D> r, v, w;
  Vector4T<D> q;
};
template <class D>
SeededState<D> seeded_state(const BodyNumbers& s, int first) {
  constexpr int variables = D::DerType::SizeAtCompileTime;
  SeededState<D> out;
  for (int k = 0; k < 3; ++k) {
    out.r[k] = D(s[k], variables, first + k);
    out.v[k] = D(s[7 + k], variables, first + 7 + k);
    out.w[k] = D(s[10 + k], variables, first + 10 + k);
  }
  for (int k = 0; k < 4; ++k) out.q[k] = D(s[3 + k], variables, first + 3 + k);
  return out;
}
template <class D>
SeededState<D> seeded_state(const Eigen::VectorXd& y, const StateLayout& l, Eigen::Index i, int first) {
  return seeded_state<D>(body_numbers(y, l, i), first);
}
inline BodyFrameT<Dual> seeded_frame(const BodyNumbers& s, int first) {
  const SeededState<Dual> seeded = seeded_state<Dual>(s, first);
  return body_frame<Dual>(seeded.r, seeded.q, seeded.v, seeded.w);
}
inline BodyFrameT<Dual> seeded_frame(const Eigen::VectorXd& y, const StateLayout& l, Eigen::Index i, int first) {
  return seeded_frame(body_numbers(y, l, i), first);
}

// The kinematic joints' view of a body's frame.
inline BodyMotionT<Dual> motion(const BodyFrameT<Dual>& f) {
  BodyMotionT<Dual> m;
  m.r = f.pos;
  m.R = f.rot;
  m.v = f.vel;
  m.w = f.omega;
  return m;
}

// The index in y of body b's state number c (0..12, in seeded_frame's order).
inline Eigen::Index state_index(const StateLayout& l, Eigen::Index b, int c) {
  if (c < 3) return l.position(b) + c;
  if (c < 7) return l.orientation(b) + c - 3;
  if (c < 10) return l.velocity(b) + c - 7;
  return l.angular_velocity(b) + c - 10;
}

}  // namespace mbsflow::jacobian_seeds
