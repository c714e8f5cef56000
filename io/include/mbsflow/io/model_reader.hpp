#pragma once
// Reads a model file (JSON, see docs/model-format.md) and checks it completely.
// Every problem is an InputError "file:line:col: field.path: what is wrong".
#include <cstddef>
#include <string>
#include <string_view>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

// The largest model file read (a 100 000-body model has about 63 MB); a run across hosts
// sends the model in one message, so this is also the cap of a control message.
inline constexpr std::size_t max_model_bytes = std::size_t{1} << 30;

Model read_model_file(const std::string& path);
// The text of a model file, checked for size as read_model_file does.
std::string read_model_file_text(const std::string& path);
// `name` is used in messages in place of a file name.
Model read_model_text(std::string_view text, const std::string& name);

}  // namespace mbsflow
