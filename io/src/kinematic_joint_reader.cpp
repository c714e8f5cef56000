// The fields of the kinematic joints: frames or axes, rigid or compliant, motor, limits.
#include <Eigen/Geometry>
#include <cmath>

#include "model_fields.hpp"

namespace mbsflow {
namespace {

using model_fields::unit_quat;
using model_fields::vec3;

Eigen::Quaterniond quaternion(const Quat& q) { return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(); }
Quat quat(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

Eigen::Vector3d unit_axis(const JsonNode& n) {
  const Vec3 a = n.fixed<3>();
  const Eigen::Vector3d v(a[0], a[1], a[2]);
  if (!(v.norm() > 1e-12)) n.fail("has zero length: an axis needs a direction");
  return v.normalized();
}

// The joint frame whose z axis is the given axis (the smallest rotation from z).
Quat frame_from_axis(const JsonNode& n) {
  return quat(Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), unit_axis(n)));
}

Eigen::Vector3d world_z(const Model& m, int body, const Quat& frame) {
  const Eigen::Quaterniond q = body == ground ? Eigen::Quaterniond::Identity()
                                              : quaternion(m.bodies[static_cast<std::size_t>(body)].orientation);
  return q * (quaternion(frame) * Eigen::Vector3d::UnitZ());
}

Eigen::Vector3d world_point(const Model& m, int body, const Vec3& p) {
  const Eigen::Vector3d local(p[0], p[1], p[2]);
  if (body == ground) return local;
  const Body& b = m.bodies[static_cast<std::size_t>(body)];
  return Eigen::Vector3d(b.position[0], b.position[1], b.position[2]) + quaternion(b.orientation) * local;
}

Vec6 non_negative6(const JsonNode& n) {
  const Vec6 v = n.fixed<6>();
  for (std::size_t i = 0; i < 6; ++i) n.item(i).non_negative();
  return v;
}

bool has_axis_dof(JointType t) { return t == JointType::revolute || t == JointType::prismatic; }

void frames(const JsonNode& n, const Model& m, Joint& j) {
  for (const char* pair : {"1", "2"}) {
    const std::string frame = std::string("frame") + pair, axis = std::string("axis") + pair;
    if (n.has(frame.c_str()) && n.has(axis.c_str())) n[axis.c_str()].fail_at_key("give either " + frame + " or " + axis + ", not both");
  }
  if (auto f = n.find("frame1")) j.frame1 = unit_quat(*f);
  if (auto a = n.find("axis1")) j.frame1 = frame_from_axis(*a);
  if (auto f = n.find("frame2")) {
    j.frame2 = unit_quat(*f);
  } else {
    // At rest by default: the two frames coincide in the initial configuration; an axis2
    // turns that frame so that its z is axis2.
    j.frame2 = rest_frame2(m, j);
    if (auto a = n.find("axis2")) {
      const Eigen::Quaterniond rest = quaternion(j.frame2);
      j.frame2 = quat((Eigen::Quaterniond::FromTwoVectors(rest * Eigen::Vector3d::UnitZ(), unit_axis(*a)) * rest).normalized());
    }
  }
  if (j.type == JointType::universal) {
    if (!n.has("axis2") && !n.has("frame2"))
      n.fail("a universal joint needs axis2 (the cross arm on body2, perpendicular to axis1)");
    const double c = world_z(m, j.body1, j.frame1).dot(world_z(m, j.body2, j.frame2));
    if (std::abs(c) > 1e-6)
      (n.has("axis2") ? n["axis2"] : n["frame2"]).fail("must be perpendicular to axis1 in the initial configuration (cosine " +
                                                         number_text(c) + ")");
  }
}

void motor(const JsonNode& n, Joint& j) {
  n.allow_only({"type", "function"});
  const JsonNode type = n["type"];
  const std::string t = type.string();
  JointMotor::Kind kind = JointMotor::Kind::none;
  if (t == "position") kind = JointMotor::Kind::position;
  else if (t == "velocity") kind = JointMotor::Kind::velocity;
  else if (t == "effort") kind = JointMotor::Kind::effort;
  else type.fail("must be one of position, velocity, effort (got '" + t + "')");
  j.motor.edit() = {kind, model_fields::time_function(n["function"])};
}

void limits(const JsonNode& n, Joint& j) {
  n.allow_only({"lower", "upper", "stiffness", "damping"});
  JointLimits& l = j.limits.edit();
  l.active = true;
  l.lower = n["lower"].number();
  l.upper = n["upper"].number();
  if (!(l.upper > l.lower)) n["upper"].fail("must be > lower (" + number_text(l.lower) + ")");
  l.stiffness = n["stiffness"].positive();
  l.damping = n.find("damping") ? n["damping"].non_negative() : 0.0;
}

}  // namespace

void read_kinematic_joint(const JsonNode& n, const Model& m, Joint& j) {
  n.allow_only({"name", "type", "body1", "body2", "point1", "point2", "frame1", "frame2", "axis1", "axis2", "rigid",
                "frequency", "damping_ratio", "stiffness", "damping", "motor", "limits", "length", "pitch"});
  const std::string type = joint_type_name(j.type);
  if (auto r = n.find("rigid")) {
    j.rigid = r->boolean();
  }
  frames(n, m, j);
  if (n.has("length") && j.type != JointType::distance) n["length"].fail_at_key("only a distance joint has a length");
  if (n.has("pitch") && j.type != JointType::screw) n["pitch"].fail_at_key("only a screw joint has a pitch");
  if (j.type == JointType::screw) {
    j.rest_length = n["pitch"].number();
    if (j.rest_length == 0.0) n["pitch"].fail("must be nonzero: the advance per turn (m; negative for a left-hand thread)");
  }
  if (j.type == JointType::distance) {
    if (auto l = n.find("length")) {
      j.rest_length = l->positive();
    } else {
      j.rest_length = (world_point(m, j.body2, j.point2) - world_point(m, j.body1, j.point1)).norm();
      if (!(j.rest_length > 1e-12)) n.fail("the two points coincide initially: give a positive 'length'");
    }
  }
  for (const char* key : {"motor", "limits"})
    if (n.has(key) && !has_axis_dof(j.type))
      n[key].fail_at_key("a " + type + " joint has no single axis to drive or limit (motors and limits go on "
                         "revolute and prismatic joints)");
  if (auto mo = n.find("motor")) motor(*mo, j);
  if (auto l = n.find("limits")) limits(*l, j);
  if (j.rigid) {
    for (const char* key : {"frequency", "damping_ratio", "stiffness", "damping"})
      if (n.has(key)) n[key].fail_at_key("only a compliant joint (\"rigid\": false) has a " + std::string(key));
    return;
  }
  if (n.has("stiffness")) {  // per joint-frame axis, as a bushing's (what the model writer gives)
    for (const char* key : {"frequency", "damping_ratio"})
      if (n.has(key)) n[key].fail_at_key("give either stiffness/damping or frequency/damping_ratio, not both");
    j.stiffness = non_negative6(n["stiffness"]);
    if (auto d = n.find("damping")) j.damping = non_negative6(*d);
    return;
  }
  if (n.has("damping")) n["damping"].fail_at_key("needs 'stiffness'");
  if (!n.has("frequency")) n.fail("a compliant joint (\"rigid\": false) needs 'frequency' (rad/s)");
  const double mu = n.find("damping_ratio") ? n["damping_ratio"].non_negative() : 0.0;
  set_bushing_from_frequency(m, j, n["frequency"].positive(), mu);
}

}  // namespace mbsflow
