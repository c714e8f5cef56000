#include "constraint_rows.hpp"

#include "as_eigen.hpp"

namespace mbsflow {

JointGeometry joint_geometry(const Joint& j) {
  JointGeometry g;
  g.type = j.type;
  g.pa = vec(j.point1);
  g.pb = vec(j.point2);
  g.fa = rotation_matrix(vec(j.frame1));
  g.fb = rotation_matrix(vec(j.frame2));
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
    case JointType::screw: n = 5; break;
    default: return 0;
  }
  return n + (has_motor_row(g) ? 1 : 0);
}

template ConstraintRow joint_coordinate<double>(const JointGeometry&, const BodyMotion&, const BodyMotion&);
template void evaluate_constraint<double>(const JointGeometry&, const BodyMotion&, const BodyMotion&, double, ConstraintRow*);

}  // namespace mbsflow
