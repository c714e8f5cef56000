#pragma once
// Writes a model as JSON that read_model_text reads back to the same model.
#include <string>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

std::string model_to_json(const Model& model);
void write_model_file(const Model& model, const std::string& path);

}  // namespace mbsflow
