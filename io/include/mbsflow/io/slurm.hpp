#pragma once
// A cluster run launched by Slurm (`srun mbsflow run model.json --slurm -o r.h5`): every
// task runs the same command; task 0 coordinates and writes the results, the others serve
// as workers. Where each task runs comes from the step's environment (docs/cluster.md).
#include <functional>
#include <string>
#include <vector>

#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow {

// A Slurm host list as `scontrol show hostnames` expands it: "n[01-03,7],gpu[1-2]x[1-2]"
// gives n01 n02 n03 n7 gpu1x1 gpu1x2 gpu2x1 gpu2x2 (zero padding kept from the lower bound).
// InputError for an unbalanced bracket, a bad range or more than max_hosts names.
std::vector<std::string> expand_hostlist(const std::string& list, std::size_t max_hosts = 1 << 20);
// Tasks per node as Slurm writes them: "2(x3),1" gives 2 2 2 1.
std::vector<int> expand_tasks_per_node(const std::string& spec);

struct SlurmStep {
  int rank = 0;                         // SLURM_PROCID
  long job_id = 0;                      // SLURM_JOB_ID (0 if unset)
  std::vector<std::string> task_hosts;  // the node of every task, by rank
  std::vector<int> task_local;          // every task's index among the tasks on its node
  int cpus_per_task = 0;                // SLURM_CPUS_PER_TASK; 0 if not given
  int tasks() const { return static_cast<int>(task_hosts.size()); }
};

// The step this process is a task of, from the environment (get returns nullptr for an
// unset variable): SLURM_PROCID, SLURM_NTASKS, SLURM_STEP_NODELIST (or SLURM_JOB_NODELIST),
// SLURM_STEP_TASKS_PER_NODE (or SLURM_TASKS_PER_NODE), SLURM_DISTRIBUTION (block, the
// default, or cyclic). InputError, naming the variable, when one is missing or does not
// agree with the others.
using EnvLookup = std::function<const char*(const char*)>;
SlurmStep slurm_step_from_env(const EnvLookup& get);

// The ports of a run: task 0's results inbox at base_port; a task with local index l
// listens at base_port + 2 l (control) and base_port + 2 l + 1 (boundary data). The
// default base port is taken from the job id, so that two jobs sharing a node do not
// collide: 20000 + 40 (job id mod 1000), room for 20 tasks per node.
int slurm_base_port(const SlurmStep& s);

// The cluster of the step: the coordinator on task 0, a worker on every other task, all
// holding the one key pair (from the shared home) and admitting only it. A node named by a
// numeric address binds that address; one named by host name binds every interface.
ClusterConfig slurm_cluster(const SlurmStep& s, int base_port, const CurveKeyPair& keys);
// What task `rank` (> 0) of that cluster binds for its control socket.
std::string slurm_worker_listen(const SlurmStep& s, int base_port, int rank);

}  // namespace mbsflow
