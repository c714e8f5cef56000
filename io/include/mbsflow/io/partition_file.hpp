#pragma once
// A decomposition saved as JSON, so that a run can reuse (or a user can hand-edit) the
// assignment of bodies to submodels:
//   {"model": "chain-2000", "bodies": 2000, "partitions": 4, "part_of_body": [0, 0, ...]}
#include <string>

#include "mbsflow/graph/decomposition.hpp"

namespace mbsflow {

void write_partition_file(const Model& model, const Decomposition& d, const std::string& path);
// InputError if the file does not match the model (name, body count, parts).
Decomposition read_partition_file(const Model& model, const std::string& path);

}  // namespace mbsflow
