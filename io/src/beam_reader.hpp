#pragma once
// One item of a model file's "beams" list as node bodies and element bushings.
#include <string>

#include "json_node.hpp"
#include "mbsflow/graph/beams.hpp"

namespace mbsflow {

// The beam n describes, its first node to be body first_body; `name` gets the beam's name.
// Fails naming the field (as JsonNode::fail) on bad data.
BeamParts read_beam(const JsonNode& n, int first_body, std::string& name);

}  // namespace mbsflow
