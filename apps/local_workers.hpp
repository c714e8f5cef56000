#pragma once
// mbsflow run --processes N: N workers on this host, started as child processes of this
// program (`mbsflow worker`), listening on loopback tcp or ipc, and stopped with it.
#include <sys/types.h>

#include <string>
#include <vector>

#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow::cli {

class LocalWorkers {
 public:
  // Starts n workers with `threads` threads each; RunError if one does not come up.
  // Their errors, if any, appear on this process's stderr.
  LocalWorkers(int n, const std::string& transport, int threads);
  ~LocalWorkers();  // waits a moment for the workers to end, then kills what is left
  LocalWorkers(const LocalWorkers&) = delete;
  LocalWorkers& operator=(const LocalWorkers&) = delete;

  const ClusterConfig& cluster() const { return cluster_; }

 private:
  std::vector<pid_t> pids_;
  std::string ipc_dir_;  // for ipc endpoints; removed at the end
  ClusterConfig cluster_;
};

}  // namespace mbsflow::cli
