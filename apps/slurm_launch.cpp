#include "slurm_launch.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "commands.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow::cli {

// A task 0 that fails before it calls (a bad model) leaves the others waiting this long;
// srun --kill-on-bad-exit=1 ends them at once.
constexpr double worker_wait_s = 600.0;

SlurmLaunch slurm_launch(int port, const std::string& key_stem) {
  SlurmLaunch s;
  s.step = slurm_step_from_env([](const char* name) { return static_cast<const char*>(std::getenv(name)); });
  s.base_port = port > 0 ? port : slurm_base_port(s.step);
  std::string stem = key_stem;
  if (stem.empty()) {
    const char* home = std::getenv("HOME");
    if (!home) throw InputError("--slurm: HOME is not set; give the key pair with --slurm-key STEM");
    stem = std::string(home) + "/.mbsflow/cluster";
  }
  if (!std::filesystem::exists(stem + ".key"))
    throw InputError("--slurm: no key pair at " + stem + ".key: make one once, in the home the nodes share, with "
                     "`mbsflow keygen " + stem + "` (every task of the run uses it)");
  s.keys = read_secret_key_file(stem + ".key");
  return s;
}

int serve_slurm_task(const SlurmLaunch& s, int threads, bool quiet) {
  const SlurmStep& st = s.step;
  const std::string& host = st.task_hosts[static_cast<std::size_t>(st.rank)];
  WorkerOptions o;
  o.listen = slurm_worker_listen(st, s.base_port, st.rank);
  // Threads: --threads, else Slurm's cpus per task, else this node's cores shared by its tasks.
  const auto on_node = std::count(st.task_hosts.begin(), st.task_hosts.end(), host);
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  o.threads = threads > 0 ? threads : st.cpus_per_task > 0 ? st.cpus_per_task : std::max(1, cores / static_cast<int>(on_node));
  o.idle_timeout_s = worker_wait_s;
  o.keys = s.keys;
  o.admit.coordinator = s.keys.public_key;
  o.admit.workers.assign(static_cast<std::size_t>(st.tasks() - 1), s.keys.public_key);
  return serve_worker_command(std::move(o), quiet);
}

}  // namespace mbsflow::cli
