#pragma once
// Field readers shared by the parts of the model reader.
#include "json_node.hpp"
#include "mbsflow/graph/model.hpp"

namespace mbsflow::model_fields {

Vec3 vec3(const JsonNode& parent, const char* key, Vec3 fallback = {});
Quat unit_quat(const JsonNode& n);  // a unit quaternion [w, x, y, z] (norm within 1e-6 of 1)
TimeFunction time_function(const JsonNode& n);

}  // namespace mbsflow::model_fields

namespace mbsflow {
// The fields of a kinematic joint (revolute ... distance) after name, type and bodies.
void read_kinematic_joint(const JsonNode& n, const Model& m, Joint& j);
}  // namespace mbsflow
