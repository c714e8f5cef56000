#pragma once
// Reads a model file (JSON, see docs/model-format.md) and checks it completely.
// Every problem is an InputError "file:line:col: field.path: what is wrong".
#include <string>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

Model read_model_file(const std::string& path);
// `name` is used in messages in place of a file name.
Model read_model_text(const std::string& text, const std::string& name);

}  // namespace mbsflow
