#pragma once
// The kinematic joints in maximal coordinates: each joint is a few scalar constraint
// equations phi(positions, t) = 0 between the joint frame on body a (body1) and the one
// on body b (body2), built from four basic ones (Haug's): a point offset along an axis of
// frame a, two axes kept perpendicular, a distance, and the angle about the joint axis.
// A row gives what an index-1 solve and a projection need, with V = (v_a, w_a, v_b, w_b)
// and A its time derivative, world frame, angular velocities of the bodies in world frame:
//   phi' = j . V + rate,   phi'' = j . A + bias.
// Templates on the scalar, like force_laws.hpp: the right-hand side evaluates the rows in
// double (instantiated once, in constraint_rows.cpp), the analytic Jacobian of compliant
// joints in forward-mode dual numbers, so both read one piece of arithmetic.
#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <type_traits>

#include "mbsflow/graph/model.hpp"
#include "rotation.hpp"

namespace mbsflow {

template <class S>
struct BodyMotionT {
  Vector3T<S> r = Vector3T<S>::Zero();  // centre of mass
  Matrix3T<S> R = Matrix3T<S>::Identity();  // body to world
  Vector3T<S> v = Vector3T<S>::Zero();  // of the centre of mass
  Vector3T<S> w = Vector3T<S>::Zero();  // angular velocity, world frame
};
using BodyMotion = BodyMotionT<double>;

template <class S>
using RowJacobianT = Eigen::Matrix<S, 12, 1>;  // v_a, w_a, v_b, w_b
using RowJacobian = RowJacobianT<double>;

template <class S>
struct ConstraintRowT {
  S phi = S(0.0);   // violation; 0 for a velocity-level row
  S rate = S(0.0);  // phi' - j . V
  S bias = S(0.0);  // phi'' - j . A
  RowJacobianT<S> j = RowJacobianT<S>::Zero();
  int axis = 0;       // the joint-frame direction it holds: 0..2 along x y z, 3..5 about x y z
  bool holonomic = true;
};
using ConstraintRow = ConstraintRowT<double>;

// A kinematic joint ready to evaluate: points in each body's frame, frame axes (columns
// x, y, z) in each body's frame, the rod length, the motor and the limits.
struct JointGeometry {
  JointType type = JointType::spherical;
  Eigen::Vector3d pa = Eigen::Vector3d::Zero(), pb = Eigen::Vector3d::Zero();
  Eigen::Matrix3d fa = Eigen::Matrix3d::Identity(), fb = Eigen::Matrix3d::Identity();
  double length = 0.0;  // distance: the rod's; screw: the lead per turn
  JointMotor motor;
  JointLimits limits;
};

JointGeometry joint_geometry(const Joint& joint);

inline bool has_motor_row(const JointGeometry& g) {
  return g.motor.kind == JointMotor::Kind::position || g.motor.kind == JointMotor::Kind::velocity;
}

// Rows of the joint's constraint: its own, plus one for a position or velocity motor.
int constraint_rows(const JointGeometry& g);

namespace rows_detail {

// Terms every row of a joint shares: the arms from each centre of mass to its joint
// point, the separation d of the points and its rate, and the centripetal accelerations
// w x (w x s) of the points.
template <class S>
struct Pair {
  Vector3T<S> sa, sb, d, dd, ca, cb;
};

template <class S>
Pair<S> pair(const JointGeometry& g, const BodyMotionT<S>& a, const BodyMotionT<S>& b) {
  Pair<S> p;
  p.sa = a.R * g.pa.cast<S>();
  p.sb = b.R * g.pb.cast<S>();
  p.d = b.r + p.sb - a.r - p.sa;
  p.dd = b.v + b.w.cross(p.sb) - a.v - a.w.cross(p.sa);
  p.ca = a.w.cross(a.w.cross(p.sa));
  p.cb = b.w.cross(b.w.cross(p.sb));
  return p;
}

template <class S>
void set_j(ConstraintRowT<S>& r, const Vector3T<S>& va, const Vector3T<S>& wa, const Vector3T<S>& vb, const Vector3T<S>& wb) {
  r.j << va, wa, vb, wb;
}

// phi = e . d, e fixed in body a (world components).
template <class S>
ConstraintRowT<S> along(const Pair<S>& p, const BodyMotionT<S>& a, const Vector3T<S>& e, int axis) {
  ConstraintRowT<S> r;
  r.axis = axis;
  r.phi = e.dot(p.d);
  set_j<S>(r, -e, e.cross(p.d + p.sa), e, p.sb.cross(e));
  const Vector3T<S> we = a.w.cross(e);
  r.bias = a.w.cross(we).dot(p.d) + 2.0 * we.dot(p.dd) + e.dot(p.cb - p.ca);
  return r;
}

// phi = e . f, e fixed in body a, f fixed in body b: keeps them perpendicular.
template <class S>
ConstraintRowT<S> perpendicular(const BodyMotionT<S>& a, const BodyMotionT<S>& b, const Vector3T<S>& e, const Vector3T<S>& f,
                                int axis) {
  ConstraintRowT<S> r;
  r.axis = axis;
  r.phi = e.dot(f);
  const Vector3T<S> ef = e.cross(f);
  set_j<S>(r, Vector3T<S>::Zero(), ef, Vector3T<S>::Zero(), -ef);
  const Vector3T<S> we = a.w.cross(e), wf = b.w.cross(f);
  r.bias = a.w.cross(we).dot(f) + 2.0 * we.dot(wf) + e.dot(b.w.cross(wf));
  return r;
}

// phi = (|d|^2 - L^2) / (2 L): a rod of length L between the points.
template <class S>
ConstraintRowT<S> distance(const Pair<S>& p, double length) {
  ConstraintRowT<S> r;
  const double inv = 1.0 / length;
  r.phi = 0.5 * (p.d.squaredNorm() - length * length) * inv;
  set_j<S>(r, -inv * p.d, inv * p.d.cross(p.sa), inv * p.d, inv * p.sb.cross(p.d));
  r.bias = inv * (p.dd.squaredNorm() + p.d.dot(p.cb - p.ca));
  return r;
}

// Angle of x_b about z_a measured from x_a, and its rate rows.
template <class S>
ConstraintRowT<S> angle(const BodyMotionT<S>& a, const BodyMotionT<S>& b, const Vector3T<S>& xa, const Vector3T<S>& za,
                        const Vector3T<S>& xb) {
  using std::atan2;  // and Eigen's, for automatic differentiation, by argument-dependent lookup
  ConstraintRowT<S> r;
  r.axis = 5;
  r.phi = atan2(xa.cross(xb).dot(za), xa.dot(xb));
  set_j<S>(r, Vector3T<S>::Zero(), -za, Vector3T<S>::Zero(), za);
  r.bias = a.w.cross(za).dot(b.w - a.w);
  return r;
}

// phi into (-period/2, period/2]: a shift by whole turns, which leaves the derivatives.
template <class S>
void whole_turns_off(S& phi, double period) {
  if constexpr (std::is_same_v<S, double>)
    phi = std::remainder(phi, period);
  else
    phi.value() = std::remainder(phi.value(), period);
}

// A screw's coupling: point b advances along z_a by `lead` per turn of x_b about z_a,
// phi = advance - lead angle / (2 pi). The angle jumps by 2 pi at +-pi; phi is taken
// modulo one lead so that the row holds over any number of turns.
template <class S>
ConstraintRowT<S> screw(const Pair<S>& p, const BodyMotionT<S>& a, const BodyMotionT<S>& b, const Vector3T<S>& xa,
                        const Vector3T<S>& za, const Vector3T<S>& xb, double lead) {
  const double c = lead / (2.0 * std::numbers::pi);
  ConstraintRowT<S> r = along<S>(p, a, za, 2);
  const ConstraintRowT<S> turn = angle<S>(a, b, xa, za, xb);
  r.phi -= c * turn.phi;
  whole_turns_off(r.phi, lead);
  r.j -= c * turn.j;
  r.bias -= c * turn.bias;
  return r;
}

// A motor's time function subtracted from its coordinate row.
template <class S>
void prescribe(ConstraintRowT<S>& r, const JointMotor& m, double t, bool periodic) {
  const FunctionValue f = evaluate(m.function, t);
  if (m.kind == JointMotor::Kind::position) {
    r.phi -= f.value;
    if (periodic) whole_turns_off(r.phi, 2.0 * std::numbers::pi);
    r.rate -= f.rate;
    r.bias -= f.accel;
  } else {  // velocity: a row on the rate only
    r.phi = S(0.0);
    r.holonomic = false;
    r.rate -= f.value;
    r.bias -= f.rate;
  }
}

}  // namespace rows_detail

// The joint coordinate along its axis (revolute: angle of frame b about z of frame a, in
// (-pi, pi]; prismatic: displacement of point b along z of frame a) as a row.
template <class S>
ConstraintRowT<S> joint_coordinate(const JointGeometry& g, const BodyMotionT<S>& a, const BodyMotionT<S>& b) {
  const Matrix3T<S> fa = a.R * g.fa.cast<S>();
  if (g.type == JointType::revolute) return rows_detail::angle<S>(a, b, fa.col(0), fa.col(2), b.R * g.fb.col(0).cast<S>());
  return rows_detail::along<S>(rows_detail::pair<S>(g, a, b), a, fa.col(2), 2);
}

// Fills rows[0 .. constraint_rows(g)).
template <class S>
void evaluate_constraint(const JointGeometry& g, const BodyMotionT<S>& a, const BodyMotionT<S>& b, double t,
                         ConstraintRowT<S>* rows) {
  using namespace rows_detail;
  const Pair<S> p = pair<S>(g, a, b);
  const Matrix3T<S> fa = a.R * g.fa.cast<S>(), fb = b.R * g.fb.cast<S>();
  const Vector3T<S> xa = fa.col(0), ya = fa.col(1), za = fa.col(2);
  const Vector3T<S> yb = fb.col(1), zb = fb.col(2);
  int n = 0;
  auto point = [&] {
    rows[n++] = along<S>(p, a, xa, 0);
    rows[n++] = along<S>(p, a, ya, 1);
    rows[n++] = along<S>(p, a, za, 2);
  };
  auto keep_axis = [&] {  // z_b stays along z_a: no rotation about x_a or y_a
    rows[n++] = perpendicular<S>(a, b, ya, zb, 3);
    rows[n++] = perpendicular<S>(a, b, xa, zb, 4);
  };
  auto on_axis = [&] {  // point b stays on the z axis of frame a
    rows[n++] = along<S>(p, a, xa, 0);
    rows[n++] = along<S>(p, a, ya, 1);
  };
  switch (g.type) {
    case JointType::spherical: point(); break;
    case JointType::revolute: point(); keep_axis(); break;
    case JointType::universal:
      point();
      rows[n++] = perpendicular<S>(a, b, za, zb, 3);
      break;
    case JointType::cylindrical: on_axis(); keep_axis(); break;
    case JointType::prismatic:
      on_axis();
      keep_axis();
      rows[n++] = perpendicular<S>(a, b, xa, yb, 5);
      break;
    case JointType::planar:
      rows[n++] = along<S>(p, a, za, 2);
      keep_axis();
      break;
    case JointType::fixed:
      point();
      keep_axis();
      rows[n++] = perpendicular<S>(a, b, xa, yb, 5);
      break;
    case JointType::distance: rows[n++] = distance<S>(p, g.length); break;
    case JointType::screw:
      on_axis();
      keep_axis();
      rows[n++] = screw<S>(p, a, b, xa, za, fb.col(0), g.length);
      break;
    default: return;
  }
  if (has_motor_row(g)) {
    ConstraintRowT<S> m = joint_coordinate<S>(g, a, b);
    prescribe<S>(m, g.motor, t, g.type == JointType::revolute);
    rows[n++] = m;
  }
}

extern template ConstraintRow joint_coordinate<double>(const JointGeometry&, const BodyMotion&, const BodyMotion&);
extern template void evaluate_constraint<double>(const JointGeometry&, const BodyMotion&, const BodyMotion&, double,
                                                 ConstraintRow*);

// The generalised force p along a row, as the wrench it puts on each body: force on b,
// torque on a, torque on b (world, about the centres of mass); the force on a is minus
// the force on b for every row here.
template <class S, class Out>
inline void add_row_wrench(const ConstraintRowT<S>& row, const S& p, Out&& out) {
  out.template segment<3>(0) += p * row.j.template segment<3>(6);
  out.template segment<3>(3) += p * row.j.template segment<3>(3);
  out.template segment<3>(6) += p * row.j.template segment<3>(9);
}

}  // namespace mbsflow
