#pragma once
// A decomposition saved as JSON, so that a run can reuse (or a user can hand-edit) the
// assignment of bodies to submodels:
//   {"model": "chain-2000", "bodies": 2000, "partitions": 4, "part_of_body": [0, 0, ...]}
#include <optional>
#include <string>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/run_settings.hpp"

namespace mbsflow {

void write_partition_file(const Model& model, const Decomposition& d, const std::string& path);
// InputError if the file does not match the model (name, body count, parts).
Decomposition read_partition_file(const Model& model, const std::string& path);

// The cut a request asks for: its partition file, its number of submodels or default_k
// (cut_for_run, run_request.hpp: none where plain_if_one and one submodel is all).
std::optional<Decomposition> cut_of_request(const Model& model, const RunRequest& request, int default_k,
                                            bool plain_if_one);

}  // namespace mbsflow
