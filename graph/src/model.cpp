#include "mbsflow/graph/model.hpp"

#include <cmath>

namespace mbsflow {

std::optional<int> find_body(const Model& model, const std::string& name) {
  if (name == "ground") return ground;
  for (std::size_t i = 0; i < model.bodies.size(); ++i)
    if (model.bodies[i].name == name) return static_cast<int>(i);
  return std::nullopt;
}

namespace {
// Reduced value a*b/(a+b); ground (infinite mass) leaves the other side's value.
double reduced(std::optional<double> a, double b) { return a ? (*a * b) / (*a + b) : b; }
}  // namespace

void set_bushing_from_frequency(const Model& model, Joint& joint, double omega, double mu) {
  const Body& b2 = model.bodies.at(static_cast<std::size_t>(joint.body2));
  const Body* b1 = joint.body1 == ground ? nullptr : &model.bodies.at(static_cast<std::size_t>(joint.body1));
  Vec6 k, c;
  for (int axis = 0; axis < 6; ++axis) {
    double m;
    if (axis < 3) {
      m = reduced(b1 ? std::optional<double>(b1->mass) : std::nullopt, b2.mass);
    } else {
      const auto i = static_cast<std::size_t>(axis - 3);
      m = reduced(b1 ? std::optional<double>(b1->inertia[i]) : std::nullopt, b2.inertia[i]);
    }
    k[static_cast<std::size_t>(axis)] = m * omega * omega;
    c[static_cast<std::size_t>(axis)] = 2.0 * mu * omega * m;
  }
  joint.stiffness = k;
  joint.damping = c;
}

}  // namespace mbsflow

#include "rotation.hpp"

namespace mbsflow {

Quat rest_frame2(const Model& model, const Joint& joint) {
  auto q = [](const Quat& a) { return Eigen::Vector4d(a[0], a[1], a[2], a[3]).normalized(); };
  const Eigen::Vector4d q1 = joint.body1 == ground ? Eigen::Vector4d(1, 0, 0, 0)
                                                   : q(model.bodies.at(static_cast<std::size_t>(joint.body1)).orientation);
  const Eigen::Vector4d q2 = q(model.bodies.at(static_cast<std::size_t>(joint.body2)).orientation);
  const Eigen::Vector4d f2 = quat_multiply(quat_conjugate(q2), quat_multiply(q1, q(joint.frame1)));
  return {f2[0], f2[1], f2[2], f2[3]};
}

const char* joint_type_name(JointType t) {
  switch (t) {
    case JointType::bushing: return "bushing";
    case JointType::spring: return "spring";
    case JointType::revolute: return "revolute";
    case JointType::spherical: return "spherical";
    case JointType::prismatic: return "prismatic";
    case JointType::cylindrical: return "cylindrical";
    case JointType::universal: return "universal";
    case JointType::planar: return "planar";
    case JointType::fixed: return "fixed";
    case JointType::distance: return "distance";
    case JointType::screw: return "screw";
  }
  return "?";
}

}  // namespace mbsflow
