#include "constraint_rows.hpp"

#include <cmath>
#include <numbers>

#include "rotation.hpp"

namespace mbsflow {
namespace {

using Eigen::Vector3d;

Vector3d vec(const Vec3& a) { return {a[0], a[1], a[2]}; }

// Terms every row of a joint shares: the arms from each centre of mass to its joint
// point, the separation d of the points and its rate, and the centripetal accelerations
// w x (w x s) of the points.
struct Pair {
  Vector3d sa, sb, d, dd, ca, cb;
};

Pair pair(const JointGeometry& g, const BodyMotion& a, const BodyMotion& b) {
  Pair p;
  p.sa = a.R * g.pa;
  p.sb = b.R * g.pb;
  p.d = b.r + p.sb - a.r - p.sa;
  p.dd = b.v + b.w.cross(p.sb) - a.v - a.w.cross(p.sa);
  p.ca = a.w.cross(a.w.cross(p.sa));
  p.cb = b.w.cross(b.w.cross(p.sb));
  return p;
}

void set_j(ConstraintRow& r, const Vector3d& va, const Vector3d& wa, const Vector3d& vb, const Vector3d& wb) {
  r.j << va, wa, vb, wb;
}

// phi = e . d, e fixed in body a (world components).
ConstraintRow along(const Pair& p, const BodyMotion& a, const Vector3d& e, int axis) {
  ConstraintRow r;
  r.axis = axis;
  r.phi = e.dot(p.d);
  set_j(r, -e, e.cross(p.d + p.sa), e, p.sb.cross(e));
  const Vector3d we = a.w.cross(e);
  r.bias = a.w.cross(we).dot(p.d) + 2.0 * we.dot(p.dd) + e.dot(p.cb - p.ca);
  return r;
}

// phi = e . f, e fixed in body a, f fixed in body b: keeps them perpendicular.
ConstraintRow perpendicular(const BodyMotion& a, const BodyMotion& b, const Vector3d& e, const Vector3d& f, int axis) {
  ConstraintRow r;
  r.axis = axis;
  r.phi = e.dot(f);
  const Vector3d ef = e.cross(f);
  set_j(r, Vector3d::Zero(), ef, Vector3d::Zero(), -ef);
  const Vector3d we = a.w.cross(e), wf = b.w.cross(f);
  r.bias = a.w.cross(we).dot(f) + 2.0 * we.dot(wf) + e.dot(b.w.cross(wf));
  return r;
}

// phi = (|d|^2 - L^2) / (2 L): a rod of length L between the points.
ConstraintRow distance(const Pair& p, double length) {
  ConstraintRow r;
  const double inv = 1.0 / length;
  r.phi = 0.5 * (p.d.squaredNorm() - length * length) * inv;
  set_j(r, -inv * p.d, inv * p.d.cross(p.sa), inv * p.d, inv * p.sb.cross(p.d));
  r.bias = inv * (p.dd.squaredNorm() + p.d.dot(p.cb - p.ca));
  return r;
}

// Angle of x_b about z_a measured from x_a, and its rate rows.
ConstraintRow angle(const BodyMotion& a, const BodyMotion& b, const Vector3d& xa, const Vector3d& za, const Vector3d& xb) {
  ConstraintRow r;
  r.axis = 5;
  r.phi = std::atan2(xa.cross(xb).dot(za), xa.dot(xb));
  set_j(r, Vector3d::Zero(), -za, Vector3d::Zero(), za);
  r.bias = a.w.cross(za).dot(b.w - a.w);
  return r;
}

// A motor's time function subtracted from its coordinate row.
void prescribe(ConstraintRow& r, const JointMotor& m, double t, bool periodic) {
  const FunctionValue f = evaluate(m.function, t);
  if (m.kind == JointMotor::Kind::position) {
    r.phi -= f.value;
    if (periodic) r.phi = std::remainder(r.phi, 2.0 * std::numbers::pi);
    r.rate -= f.rate;
    r.bias -= f.accel;
  } else {  // velocity: a row on the rate only
    r.phi = 0.0;
    r.holonomic = false;
    r.rate -= f.value;
    r.bias -= f.rate;
  }
}

bool has_motor_row(const JointGeometry& g) {
  return g.motor.kind == JointMotor::Kind::position || g.motor.kind == JointMotor::Kind::velocity;
}

}  // namespace

JointGeometry joint_geometry(const Joint& j) {
  JointGeometry g;
  g.type = j.type;
  g.pa = vec(j.point1);
  g.pb = vec(j.point2);
  g.fa = rotation_matrix(Eigen::Vector4d(j.frame1[0], j.frame1[1], j.frame1[2], j.frame1[3]));
  g.fb = rotation_matrix(Eigen::Vector4d(j.frame2[0], j.frame2[1], j.frame2[2], j.frame2[3]));
  g.length = j.rest_length;
  g.motor = j.motor.get();
  g.limits = j.limits.get();
  return g;
}

int constraint_rows(const JointGeometry& g) {
  int n = 0;
  switch (g.type) {
    case JointType::spherical: n = 3; break;
    case JointType::revolute: n = 5; break;
    case JointType::prismatic: n = 5; break;
    case JointType::cylindrical: n = 4; break;
    case JointType::universal: n = 4; break;
    case JointType::planar: n = 3; break;
    case JointType::fixed: n = 6; break;
    case JointType::distance: n = 1; break;
    default: return 0;
  }
  return n + (has_motor_row(g) ? 1 : 0);
}

void evaluate_constraint(const JointGeometry& g, const BodyMotion& a, const BodyMotion& b, double t, ConstraintRow* rows) {
  const Pair p = pair(g, a, b);
  const Eigen::Matrix3d fa = a.R * g.fa, fb = b.R * g.fb;
  const Vector3d xa = fa.col(0), ya = fa.col(1), za = fa.col(2);
  const Vector3d yb = fb.col(1), zb = fb.col(2);
  int n = 0;
  auto point = [&] {
    rows[n++] = along(p, a, xa, 0);
    rows[n++] = along(p, a, ya, 1);
    rows[n++] = along(p, a, za, 2);
  };
  auto keep_axis = [&] {  // z_b stays along z_a: no rotation about x_a or y_a
    rows[n++] = perpendicular(a, b, ya, zb, 3);
    rows[n++] = perpendicular(a, b, xa, zb, 4);
  };
  auto on_axis = [&] {  // point b stays on the z axis of frame a
    rows[n++] = along(p, a, xa, 0);
    rows[n++] = along(p, a, ya, 1);
  };
  switch (g.type) {
    case JointType::spherical: point(); break;
    case JointType::revolute: point(); keep_axis(); break;
    case JointType::universal:
      point();
      rows[n++] = perpendicular(a, b, za, zb, 3);
      break;
    case JointType::cylindrical: on_axis(); keep_axis(); break;
    case JointType::prismatic:
      on_axis();
      keep_axis();
      rows[n++] = perpendicular(a, b, xa, yb, 5);
      break;
    case JointType::planar:
      rows[n++] = along(p, a, za, 2);
      keep_axis();
      break;
    case JointType::fixed:
      point();
      keep_axis();
      rows[n++] = perpendicular(a, b, xa, yb, 5);
      break;
    case JointType::distance: rows[n++] = distance(p, g.length); break;
    default: return;
  }
  if (has_motor_row(g)) {
    ConstraintRow m = joint_coordinate(g, a, b);
    prescribe(m, g.motor, t, g.type == JointType::revolute);
    rows[n++] = m;
  }
}

ConstraintRow joint_coordinate(const JointGeometry& g, const BodyMotion& a, const BodyMotion& b) {
  const Eigen::Matrix3d fa = a.R * g.fa;
  if (g.type == JointType::revolute) return angle(a, b, fa.col(0), fa.col(2), b.R * g.fb.col(0));
  return along(pair(g, a, b), a, fa.col(2), 2);
}

}  // namespace mbsflow
