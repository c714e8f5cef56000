#pragma once
// The cluster file: the coordinator and workers of a multi-host run, their endpoints,
// the transport and the timeouts (docs/cluster.md).
#include <string>

#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow {

// InputError("file:line:col: field.path: what") for anything wrong.
ClusterConfig read_cluster_file(const std::string& path);
// `name` in messages; a secret_key path is taken relative to base_dir.
ClusterConfig read_cluster_text(const std::string& text, const std::string& name, const std::string& base_dir = ".");

// What a worker reads of the cluster file: the public keys it admits, and the secret key
// file the file names (empty if none; relative paths resolved against the file's folder).
struct ClusterKeyFile {
  ClusterKeys keys;
  std::string secret_key_file;
};
ClusterKeyFile read_cluster_keys(const std::string& path);

}  // namespace mbsflow
