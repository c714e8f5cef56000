#pragma once
// What a kinematic joint exerts as a force element, into out (9 rows, as force_laws.hpp's
// compliant_joint_wrench): a compliant joint's reaction -(k phi + c phi') on every
// constrained direction (the seed's compliant joint), an effort motor along the joint's
// coordinate, and its limit stops. A template on the scalar: the right-hand side runs it
// in double, the analytic Jacobian in forward-mode dual numbers.
#include <array>
#include <type_traits>

#include "constraint_rows.hpp"

namespace mbsflow {

constexpr int max_joint_rows = 7;

template <class S>
RowJacobianT<S> row_velocities(const BodyMotionT<S>& a, const BodyMotionT<S>& b) {
  RowJacobianT<S> v;
  v << a.v, a.w, b.v, b.w;
  return v;
}

// The coefficient of a row's direction: translational (x y z) or rotational (about x y z).
template <class S>
double on_axis(const ConstraintRowT<S>& r, const Eigen::Vector3d& translational, const Eigen::Vector3d& rotational) {
  return r.axis < 3 ? translational[r.axis] : rotational[r.axis - 3];
}

// Law: MultibodySystem's joint law (kt, ct, kr, cr, read where the joint is compliant,
// rigid false). out is added to. effort (double only, may be null): the motor's effort,
// where the joint has a motor.
template <class S, class Law, class Out>
void kinematic_joint_wrench(const Law& law, bool rigid, const JointGeometry& g, const BodyMotionT<S>& a, const BodyMotionT<S>& b, double t,
                            Out&& out, double* effort) {
  auto keep_effort = [effort](const S& p) {
    if constexpr (std::is_same_v<S, double>)
      if (effort) *effort = p;
  };
  const RowJacobianT<S> v = row_velocities<S>(a, b);
  if (!rigid) {  // the seed's compliant joint: -(k phi + c phi') on every constrained direction
    std::array<ConstraintRowT<S>, max_joint_rows> rows;
    const int n = constraint_rows(g);
    evaluate_constraint<S>(g, a, b, t, rows.data());
    for (int r = 0; r < n; ++r) {
      const ConstraintRowT<S>& row = rows[static_cast<std::size_t>(r)];
      const S p = -(on_axis(row, law.kt, law.kr) * row.phi + on_axis(row, law.ct, law.cr) * (row.j.dot(v) + row.rate));
      add_row_wrench<S>(row, p, out);
      if (r == n - 1 && g.motor.kind != JointMotor::Kind::none) keep_effort(p);
    }
  }
  const bool effort_motor = g.motor.kind == JointMotor::Kind::effort;
  if (!effort_motor && !g.limits.active) return;
  const ConstraintRowT<S> row = joint_coordinate<S>(g, a, b);  // the effort's and the stops' direction
  if (effort_motor) {
    const S p(evaluate(g.motor.function, t).value);
    add_row_wrench<S>(row, p, out);
    keep_effort(p);
  }
  if (g.limits.active) {
    const S rate = row.j.dot(v);
    const JointLimits& l = g.limits;
    S p(0.0);  // a stop pushes, never pulls
    if (row.phi < l.lower) {
      p = l.stiffness * (l.lower - row.phi) - l.damping * rate;
      if (!(0.0 < p)) p = S(0.0);
    }
    if (row.phi > l.upper) {
      p = -l.stiffness * (row.phi - l.upper) - l.damping * rate;
      if (!(p < 0.0)) p = S(0.0);
    }
    add_row_wrench<S>(row, p, out);
  }
}

}  // namespace mbsflow
