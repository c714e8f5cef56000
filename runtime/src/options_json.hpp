#pragma once
// The run's settings as JSON, for workers: the coordinator writes them and a worker reads
// them with this one pair of functions, so that a new setting cannot be forgotten on
// one side.
#include <nlohmann/json.hpp>

#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

nlohmann::json options_to_json(const RunOptions& o);
// InputError for an unknown method or a missing field.
RunOptions options_from_json(const nlohmann::json& j);

// Loose coupling: threads and coupling_tol stay with the process that runs the macro steps.
nlohmann::json loose_to_json(const LooseOptions& l);
LooseOptions loose_from_json(const nlohmann::json& j);

}  // namespace mbsflow
