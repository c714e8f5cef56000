#pragma once
// The dual numbers of the analytic Jacobian (analytic_jacobian.cpp, cluster_jacobian.cpp):
// a body's 13 state numbers seeded as variables, and the views of them that the force
// laws and the constraint rows take.
#include <Eigen/Core>
#include <type_traits>
#include <unordered_map>
#include <unsupported/Eigen/AutoDiff>
#include <vector>

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
// (A dual number of run-time size takes the variables' count.) velocities = false: the
// position and orientation alone as variables first..first+6, the velocities constants.
template <class D>
SeededState<D> seeded_state(const BodyNumbers& s, int first, int variables = D::DerType::SizeAtCompileTime,
                            bool velocities = true) {
  SeededState<D> out;
  for (int k = 0; k < 3; ++k) {
    out.r[k] = D(s[k], variables, first + k);
    out.v[k] = velocities ? D(s[7 + k], variables, first + 7 + k) : D(s[7 + k]);
    out.w[k] = velocities ? D(s[10 + k], variables, first + 10 + k) : D(s[10 + k]);
  }
  for (int k = 0; k < 4; ++k) out.q[k] = D(s[3 + k], variables, first + 3 + k);
  return out;
}
// x's numbers as the variables first.. (of `variables`).
template <class D>
Eigen::Matrix<D, Eigen::Dynamic, 1> seeded_values(const Eigen::VectorXd& x, int first, int variables) {
  Eigen::Matrix<D, Eigen::Dynamic, 1> out(x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) out[k] = D(x[k], variables, first + static_cast<int>(k));
  return out;
}
// A flexible body's frame numbers, then its eta and eta', as the variables first..
// first + 13 + 2 ne - 1 of `variables`.
template <class D>
struct SeededModes : SeededState<D> {
  Eigen::Matrix<D, Eigen::Dynamic, 1> eta, eta_rate;
};
template <class D>
SeededModes<D> seeded_modes(const BodyNumbers& frame, const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, int first,
                            int variables) {
  SeededModes<D> out{seeded_state<D>(frame, first, variables), {}, {}};
  out.eta = seeded_values<D>(eta, first + body_states, variables);
  out.eta_rate = seeded_values<D>(eta_rate, first + body_states + static_cast<int>(eta.size()), variables);
  return out;
}
template <class D>
SeededState<D> seeded_state(const Eigen::VectorXd& y, const StateLayout& l, Eigen::Index i, int first) {
  return seeded_state<D>(body_numbers(y, l, i), first);
}
// A joint's dual numbers over the position and orientation alone of its two bodies (7
// each), the velocities constants: its stiffness at rest in about half of Dual's work.
constexpr int body_positions = 7;
using PositionDual = Eigen::AutoDiffScalar<Eigen::Matrix<double, 2 * body_positions, 1>>;
// A body's frame with its numbers as variables from first on: all 13 in Dual, the
// position and orientation alone in PositionDual.
template <class D = Dual>
BodyFrameT<D> seeded_frame(const BodyNumbers& s, int first) {
  const SeededState<D> seeded = seeded_state<D>(s, first, D::DerType::SizeAtCompileTime, !std::is_same_v<D, PositionDual>);
  return body_frame<D>(seeded.r, seeded.q, seeded.v, seeded.w);
}
inline BodyFrameT<Dual> seeded_frame(const Eigen::VectorXd& y, const StateLayout& l, Eigen::Index i, int first) {
  return seeded_frame(body_numbers(y, l, i), first);
}

// The kinematic joints' view of a body's frame.
template <class D>
BodyMotionT<D> motion(const BodyFrameT<D>& f) {
  BodyMotionT<D> m;
  m.r = f.pos;
  m.R = f.rot;
  m.v = f.vel;
  m.w = f.omega;
  return m;
}

// A motion that is no variable's (ground, a driven body) in dual numbers.
template <class D>
BodyMotionT<D> constant_motion(const BodyMotion& m) {
  BodyMotionT<D> d;
  d.r = m.r.cast<D>();
  d.R = m.R.cast<D>();
  d.v = m.v.cast<D>();
  d.w = m.w.cast<D>();
  return d;
}

// The index in y of body b's state number c (0..12, in seeded_frame's order).
inline Eigen::Index state_index(const StateLayout& l, Eigen::Index b, int c) {
  if (c < 3) return l.position(b) + c;
  if (c < 7) return l.orientation(b) + c - 3;
  if (c < 10) return l.velocity(b) + c - 7;
  return l.angular_velocity(b) + c - 10;
}

// Dual numbers over a number of variables known at run time: up to 64 derivatives on the
// stack (the heap's allocations were half the time of a flexible body's Jacobian), beyond
// that on the heap.
constexpr int stack_variables = 64;
using StackDual = Eigen::AutoDiffScalar<Eigen::Matrix<double, Eigen::Dynamic, 1, 0, stack_variables, 1>>;
using HeapDual = Eigen::AutoDiffScalar<Eigen::VectorXd>;

// The derivatives of x by the variables (a constant's are empty: zero).
template <class D>
Eigen::VectorXd derivatives_of(const D& x, int variables) {
  return x.derivatives().size() == variables ? Eigen::VectorXd(x.derivatives()) : Eigen::VectorXd::Zero(variables);
}
// Rows of the derivatives of a vector of dual numbers into out, from row `first`.
template <class V>
void put_rows(const V& v, Eigen::Index first, int variables, Eigen::MatrixXd& out) {
  for (Eigen::Index r = 0; r < v.size(); ++r) out.row(first + r) = derivatives_of(v[r], variables).transpose();
}

// The variables of an evaluation in dual numbers over a varying set of state numbers:
// indices into y, numbered in the order first met.
struct Variables {
  std::vector<Eigen::Index> cols;
  std::unordered_map<Eigen::Index, int> number;
  int of(Eigen::Index col) {
    const auto [at, added] = number.emplace(col, static_cast<int>(cols.size()));
    if (added) cols.push_back(col);
    return at->second;
  }
  int count() const { return static_cast<int>(cols.size()); }
  // Derivatives given as (index into y, column) pairs, summed into columns by variable.
  template <class Parts>
  Eigen::MatrixXd gather(const Parts& parts, Eigen::Index rows) const {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(rows, count());
    for (const auto& [col, d] : parts) out.col(number.at(col)) += d;
    return out;
  }
};

}  // namespace mbsflow::jacobian_seeds
