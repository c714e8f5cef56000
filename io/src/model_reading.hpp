#pragma once
// The two readers behind read_model_text. The fast one (json_tape.hpp) reads the plain
// JSON that mbsflow and most tools write; where it gives up (text outside its subset, or
// a model with an error) the reference reader, nlohmann-json's, reads the text again, so
// that every message is the reference's. Both give the same model wherever both read.
#include <optional>
#include <string>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

std::optional<Model> read_model_fast(std::string_view text, const std::string& name);
Model read_model_reference(std::string_view text, const std::string& name);

}  // namespace mbsflow
