#pragma once
// The cluster file: the coordinator and workers of a multi-host run, their endpoints,
// the transport and the timeouts (docs/cluster.md).
#include <string>

#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow {

// InputError("file:line:col: field.path: what") for anything wrong.
ClusterConfig read_cluster_file(const std::string& path);
ClusterConfig read_cluster_text(const std::string& text, const std::string& name);

}  // namespace mbsflow
