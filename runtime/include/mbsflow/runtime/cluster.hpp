#pragma once
// Runs across processes and hosts over ZeroMQ. A coordinator (run_cluster) hands the model
// and the assignment of submodels to workers (serve_worker), which exchange boundary values
// peer to peer at every RK4 or DOPRI5 stage and stream their bodies' snapshots back; the results are
// bitwise those of the one-process run. See docs/cluster.md for the cluster file and the
// protocol.
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/curve_keys.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

// Raised with every incompatible change of the messages between processes.
constexpr int cluster_protocol_version = 7;  // 2: loose coupling records, newest-value lag; 3: tight DOPRI5; 4: run ids, frame versions; 5: checkpoints; 6: the set-up's model in a frame of its own; 7: part_of_body as text

struct ClusterTimeouts {
  double connect_s = 10.0;   // every worker must answer the coordinator's hello within this
  double heartbeat_s = 0.5;  // both directions
  double lost_s = 3.0;       // silence after which a peer counts as lost
  // A worker whose computation has not advanced this long (a step that never ends, while
  // its heartbeats go on) is hung; time spent waiting for its peers does not count.
  double stall_s = 60.0;
  // The largest values accepted from a cluster file or the wire: a peer's hello cannot
  // hold a worker longer than these (a worker waits at most connect_s + lost_s for the
  // set-up after the hello), nor make milliseconds overflow.
  static constexpr double max_connect_s = 600.0, max_heartbeat_s = 30.0, max_lost_s = 600.0, max_stall_s = 86400.0;
};

struct ClusterWorker {
  std::string name;
  std::string address;       // where the coordinator reaches its control socket (`mbsflow worker --listen`)
  std::string data_bind;     // where it binds its inbox for boundary values
  std::string data_address;  // where its peers reach that inbox; empty: what data_bind bound
  int weight = 1;            // takes `weight` submodels when no explicit list is given
  std::vector<int> submodels;  // explicit submodel numbers; all workers or none have them
  int threads = 0;           // 0: the worker's own --threads (default all cores)
  std::string public_key;    // its CURVE public key (Z85)
};

// A run without CURVE must be asked for, and only on loopback unless asked for anywhere.
enum class Insecure { no, loopback, anywhere };

struct ClusterConfig {
  std::string transport = "tcp";  // tcp or ipc
  std::string coordinator_name = "coordinator";
  std::string results_bind;     // where the coordinator binds the inbox for the workers' results
  std::string results_address;  // where the workers reach it; empty: what results_bind bound
  std::vector<ClusterWorker> workers;
  ClusterTimeouts timeouts;
  // Security (docs/reliability.md): the coordinator's public key and this host's key pair
  // (the cluster file's secret_key file); without them the run is refused unless insecure.
  std::string coordinator_key;
  std::optional<CurveKeyPair> keys;
  Insecure insecure = Insecure::no;
};

// InputError unless the run is secured by keys (every worker's public key, the local pair
// the coordinator's) or insecure as asked (every endpoint on loopback for Insecure::loopback).
void check_cluster_security(const ClusterConfig& c);

// Submodels a cluster run is cut into when the user does not say: the explicit lists'
// length, or the sum of the weights.
int cluster_submodels(const ClusterConfig& c);
// The worker of each of k submodels: the explicit lists, or contiguous runs of submodels
// in proportion to the weights. InputError if a list is wrong for k.
std::vector<int> assign_submodels(const ClusterConfig& c, int k);

struct ClusterStats {
  long messages = 0;             // boundary messages between workers in the run
  double bytes_per_stage = 0.0;  // boundary payload sent by all workers per stage
  double setup_seconds = 0.0;    // hello to start: versions, model, sockets (not in RunSummary::wall_seconds)
  std::vector<CouplingRecord> coupling;  // loose coupling: per macro step, over all workers
};

// The coordinator. model_json is the model as written by model_to_json, which every worker
// reads back to the same Model. Tight coupling: RK4 or DOPRI5. Throws RunError naming the
// worker when one is lost or fails; InputError for bad settings.
struct LooseOptions;

// How the workers are coupled: tight (every stage) unless loose is set (macro steps,
// RK4 or DOPRI5 inside; a fixed macro step). exchange_delay_s holds every boundary message
// back that long (a slow network, for tests and the benchmark).
struct ClusterCoupling {
  const LooseOptions* loose = nullptr;
  double exchange_delay_s = 0.0;
};

RunSummary run_cluster(const Model& model, const std::string& model_json, const Decomposition& d,
                       const ClusterConfig& cluster, const RunOptions& options, ResultSink* sink,
                       ClusterStats* stats = nullptr, ClusterCoupling coupling = {});
// The same with a model the caller holds shared: the whole system (for the sink) shares it.
RunSummary run_cluster(std::shared_ptr<const Model> model, const std::string& model_json, const Decomposition& d,
                       const ClusterConfig& cluster, const RunOptions& options, ResultSink* sink,
                       ClusterStats* stats = nullptr, ClusterCoupling coupling = {});
// The checks run_cluster makes of its settings before it contacts anyone (InputError);
// callers that start workers first call it before.
void check_cluster_run(const Model& model, const RunOptions& options, const ClusterCoupling& coupling);

struct WorkerOptions {
  std::string listen;  // control endpoint to bind; a tcp port of * picks a free one
  int threads = 0;     // 0: all cores (the coordinator's cluster file may set it)
  double idle_timeout_s = 0.0;  // give up when no coordinator calls within this; 0: wait forever
  int protocol_version = cluster_protocol_version;  // tests pretend another
  std::function<Model(const std::string& json)> read_model;
  std::function<void(const std::string& endpoint)> listening;  // told the bound endpoint
  std::function<void(const std::string& line)> log;             // what the worker does, for its log
  const std::atomic<bool>* stop = nullptr;
  // CURVE: this worker's key pair and the public keys it admits (the cluster file's): the
  // coordinator's on the control socket, the workers' on the data inbox. Without keys the
  // worker serves only when insecure is asked for (on loopback unless anywhere).
  std::optional<CurveKeyPair> keys;
  ClusterKeys admit;
  Insecure insecure = Insecure::no;
  double hang_after_s = -1.0;  // tests: >= 0 makes the computation spin (a hung step) this long into the run
};

// One worker session: waits for a coordinator, runs its part of one run and returns when
// the coordinator finishes it. RunError when the run fails or the coordinator is lost;
// InputError when the endpoint cannot be bound.
void serve_worker(const WorkerOptions& options);

}  // namespace mbsflow
