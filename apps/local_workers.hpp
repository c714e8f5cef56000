#pragma once
// mbsflow run --processes N: N workers on this host, started as child processes of this
// program (`mbsflow worker`), listening on loopback tcp or ipc, and stopped with it; the
// run is authenticated with key pairs made for it (CURVE).
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
  std::string ipc_dir_;  // owner-only: ipc endpoints and the run's keys; removed at the end
  ClusterConfig cluster_;
};

}  // namespace mbsflow::cli
