#pragma once
// What a worker's run loops (worker_part, worker_tight, worker_loose) need from the
// transport, with no transport type in sight: the boundary exchange with the other
// workers, the results channel to the coordinator, and the coordinator's commands. The
// ZeroMQ transport implements them (remote_exchange.hpp, worker_io.hpp,
// zmq_worker_transport.cpp); another transport is another implementation of these three.
#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "boundary_exchange.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "wire_format.hpp"

namespace mbsflow {

struct Session;  // worker_part.hpp

// The exchange of a worker's local submodels with the other workers' submodels: the
// stages of a tight run (BoundaryExchange), the macro steps of a loose one with their
// rollback, and the reductions over all workers.
class WorkerExchange : public BoundaryExchange {
 public:
  // Stage input 0 of steps up to n is not exchanged: every process holds it (a loose run's
  // macro-step end 0). A tight run offers the state it starts from instead (its ghosts'
  // own copies are the model's, which the owner may have projected onto rigid joints).
  virtual void start_at(long n) = 0;
  // From local p's stage: its remote ghosts of stage input s of step n, from their slots.
  virtual void receive(int p, long n, int s) = 0;
  // From local p (loose coupling): remote q's messages of stage input s with a step up to
  // cap that are in, oldest first, to take(step, values).
  virtual void take_upto(int p, int q, int s, long cap, const std::function<void(long, const double*)>& take) = 0;
  // From local p's stage: its bodies of stage input s of step n to the remote submodels
  // that hold them as ghosts.
  virtual void send(int p, long n, int s) = 0;
  // The same from a state x of local p (a resumed loose run sends its kept macro-step ends again).
  virtual void send(int p, long n, int s, const Eigen::VectorXd& x) = 0;
  // Loose coupling's error control, before a macro step to end n is taken again: the
  // messages of stage input s of step n that were taken are forgotten, so that waiting
  // for step n waits for the new ones (any that are in already count).
  virtual void rewind(int s, long n) = 0;
  // The largest of every worker's `mine` (loose coupling's error control: all take the
  // same decision); n numbers the call (the same in every worker).
  virtual double max_over_workers(long n, double mine) = 0;

  // Stops the exchange: waiting proxies return and stages skip their work.
  virtual void abort(const std::string& why) = 0;
  virtual bool aborted() const = 0;
  virtual std::string why() const = 0;
  virtual long messages_sent() const = 0;
  virtual double bytes_per_stage() const = 0;  // payload this worker sends per stage
};

// Worker -> coordinator: results (snapshots, progress, checkpoints, the end).
class ResultsChannel {
 public:
  virtual ~ResultsChannel() = default;
  // A header and its payload; false when the coordinator stopped taking them.
  virtual bool send(const wire::ResultHeader& h, const void* data, std::size_t bytes) = 0;
};

// Coordinator -> worker: its commands, as the run loops see them.
class WorkerControl {
 public:
  virtual ~WorkerControl() = default;
  // The next command, {"type": "lost"} once the coordinator is lost; nullopt after
  // timeout_s (<= 0: wait as long as it takes).
  virtual std::optional<nlohmann::json> next_command(double timeout_s) = 0;
  // Stopped on the coordinator's abort or when it is lost; null: none.
  virtual void attach(WorkerExchange* exchange) = 0;
  virtual ClusterTimeouts timeouts() const = 0;
  // The computation's clock for the watchdog (wire::now_ns()): marked when a step completes.
  virtual std::atomic<std::int64_t>* progress_clock() = 0;
  // The checkpoint opportunity the coordinator asked for last, or -1.
  virtual std::int64_t checkpoint_request() const = 0;
};

// One worker's channels for one run.
class WorkerTransport {
 public:
  virtual ~WorkerTransport() = default;
  virtual WorkerControl& control() = 0;
  // The exchange of the local submodels `parts` (null where a submodel runs elsewhere),
  // `stages` stage inputs per step; start: the coordinator's "start" (the workers' names
  // and data addresses).
  virtual std::unique_ptr<WorkerExchange> exchange(const Session& s, const nlohmann::json& start,
                                                   std::vector<partitioned::Part*> parts, int stages) = 0;
  virtual std::unique_ptr<ResultsChannel> results(const Session& s) = 0;
};

}  // namespace mbsflow
