#pragma once
// What a worker's part of a run needs whatever the coupling: the run's settings as the
// coordinator sent them, its local submodels, the boundary exchange with the other
// workers, and the results channel to the coordinator.
#include <algorithm>
#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/runtime/loose_coupling.hpp"
#include "partitioned_state.hpp"
#include "wire_format.hpp"
#include "worker_transport.hpp"

namespace mbsflow {

// What the coordinator told this worker to run.
struct Session {
  Model model;
  Decomposition d;
  std::vector<int> worker_of;
  int me = 0;
  RunOptions o;
  std::string results_address;
  std::optional<LooseOptions> loose;  // loose coupling, else tight
  double exchange_delay_s = 0.0;      // added to every boundary message (tests, benchmark)
  std::vector<std::uint8_t> resume;   // the state to go on from (the coordinator's checkpoint); empty: none
  std::uint64_t run = 0;              // the run id every message carries
  int threads = 0;                    // > 0: the cluster file's threads for this worker
  std::optional<wire::Security> security;  // CURVE: the peers' public keys
  double hang_after_s = -1.0;              // tests (WorkerOptions::hang_after_s)
  // Tight coupling: the local submodels' state (null where a submodel runs elsewhere),
  // made before the worker says it is ready, so that the run's clock, which starts with
  // the coordinator's "start", does not count it (prepare_tight).
  std::vector<std::unique_ptr<partitioned::Part>> tight_parts;
  std::size_t workers() const {            // of the run: worker_of names each
    return static_cast<std::size_t>(*std::max_element(worker_of.begin(), worker_of.end())) + 1;
  }
};

struct Outcome {
  std::string failure;                         // empty when this worker's part completed
  std::optional<nlohmann::json> last_command;  // the coordinator's word after it: finish or abort
};

class WorkerPart {
 public:
  // parts[q]: local submodel q's state, null where q runs elsewhere; stages: the stage
  // inputs exchanged per step.
  WorkerPart(Session& s, WorkerTransport& transport, const nlohmann::json& start, std::vector<partitioned::Part*> parts,
             int stages, const std::atomic<bool>* stop);
  ~WorkerPart();

  Session& s;
  std::vector<partitioned::Part*> parts;
  std::vector<int> mine;  // local submodels, ascending

 private:
  std::unique_ptr<WorkerExchange> exchange_;  // the transport's; made before `exchange` refers to it

 public:
  WorkerExchange& exchange;

  // A failure message when the run must stop at time t (aborted, diverged, interrupted).
  std::string check(double t) const;
  // Own bodies of the local submodels (x[0]), packed in the order the coordinator expects.
  void pack_own(std::vector<double>& out) const;
  // Own bodies of the local submodels (x[0]) to the coordinator as snapshot number
  // `snapshot` at t, after `steps` steps; or with snapshot < 0 only the progress.
  void report_state(long steps, double t, long snapshot);
  // Own bodies of the local submodels from y (global layout): dense output at t, which the
  // coordinator projects (after_step), or a snapshot as it is (projected: false).
  void report_dense(long steps, double t, long index, const Eigen::VectorXd& y, bool project = true);
  // Loose coupling: macro-step records (loose_rounds.hpp) to the coordinator.
  void report_coupling(const std::vector<CouplingRecord>& records);
  // Checkpoints (docs/cluster.md): the run loop asks at each of its checkpoint
  // opportunities, which every worker has alike (step chunks, macro steps), numbered from
  // 1; true when the coordinator asked for this one. A request this worker is already
  // past is answered at once with the opportunity it is at, so that the coordinator can
  // ask for a later one.
  bool checkpoint_due();
  // The local state at the opportunity checkpoint_due() said yes to, to the coordinator.
  void send_checkpoint(const std::vector<std::uint8_t>& state);
  // Reports done (with the counts) or the failure, then waits for the coordinator's
  // finish or abort.
  Outcome finish(std::string failure, long steps, double t, double evaluations, long rejected = 0);

 private:
  void report(wire::ResultKind kind, long steps, double t, long index, const void* data, std::size_t bytes);
  WorkerControl& control_;
  std::unique_ptr<ResultsChannel> results_;
  const std::atomic<bool>* stop_;
  wire::Clock::time_point started_ = wire::Clock::now();
  std::vector<double> snapshot_;
  long opportunity_ = 0;
  std::int64_t answered_ = -1;  // the last request answered
  partitioned::StateShare share_;  // the local submodels' own bodies and modes, as the coordinator expects them
};

// Makes s.tight_parts; run_tight needs them.
void prepare_tight(Session& s);

// The loops, each with its local submodels' state: RK4 or DOPRI5 with values exchanged
// every stage (tight), or macro steps (loose).
Outcome run_tight(Session& s, WorkerTransport& transport, const nlohmann::json& start, int threads,
                  const std::atomic<bool>* stop);
Outcome run_loose_part(Session& s, WorkerTransport& transport, const nlohmann::json& start, int threads,
                       const std::atomic<bool>* stop);

}  // namespace mbsflow
