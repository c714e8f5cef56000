#pragma once
// A worker's I/O thread: owns the control socket (ROUTER, bound at --listen), sends
// heartbeats, notices a silent coordinator and hands commands to the worker's main thread;
// an abort or a lost coordinator stops the attached exchange at once. The ZeroMQ
// transport's WorkerControl.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <zmq.hpp>

#include "cluster_wire.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "worker_transport.hpp"

namespace mbsflow {

class WorkerIo final : public WorkerControl {
 public:
  // Binds the control socket (InputError if it cannot) and starts the thread.
  // security: CURVE on the control socket (the context's ZapGuard admits the coordinator).
  WorkerIo(zmq::context_t& ctx, const std::string& listen, const wire::Security* security);
  ~WorkerIo() override;
  WorkerIo(const WorkerIo&) = delete;
  WorkerIo& operator=(const WorkerIo&) = delete;

  const std::string& endpoint() const { return endpoint_; }
  // The next command from the coordinator, {"type": "lost"} once it is lost; nullopt
  // after timeout_s (<= 0: wait as long as it takes).
  std::optional<nlohmann::json> next_command(double timeout_s) override;
  // Sends a control message to the coordinator (on the I/O thread).
  void send(nlohmann::json message);
  // Says goodbye to the coordinator; the control socket then closes with a linger of one
  // second instead of none, so that the goodbye goes out.
  void goodbye();
  void attach(WorkerExchange* exchange) override;  // stopped on an abort or when the coordinator is lost
  ClusterTimeouts timeouts() const override;
  // The computation's clock for the watchdog: marked when a step completes and while it
  // waits for peers; heartbeats carry how long ago that was (stalled_s).
  std::atomic<std::int64_t>* progress_clock() override { return &progress_ns_; }  // wire::now_ns()
  // The checkpoint opportunity the coordinator asked for last (its "checkpoint" command,
  // which is not queued), or -1.
  std::int64_t checkpoint_request() const override { return checkpoint_at_.load(); }
  // Set once the coordinator's set-up has begun to arrive (its model may take a while).
  const std::atomic<bool>* setup_begun() const { return &setup_begun_; }

 private:
  void loop();
  void receive();  // one message of the control socket (I/O thread)
  // A hello is a few hundred bytes; before it, nothing larger is parsed.
  static constexpr std::size_t max_hello_bytes = 64 * 1024;
  void command(nlohmann::json j);
  // The set-up waits for its model, which follows in "model_part" messages; it is handed
  // on complete (with "model": the text).
  void begin_setup(nlohmann::json j);
  void take_model_part(const zmq::message_t& part);
  void lose(const std::string& why);
  void reply_error(const std::string& to, const std::string& message);  // I/O thread
  void post_locked(std::function<void()> f);  // runs f on the I/O thread; call with mutex_ held

  zmq::context_t& ctx_;
  zmq::socket_t control_;
  zmq::socket_t wake_in_, wake_out_;  // inproc PAIR: wakes the I/O thread for posted work
  std::string endpoint_;
  std::thread thread_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<nlohmann::json> commands_;
  std::deque<std::function<void()>> posted_;  // run on the I/O thread
  WorkerExchange* exchange_ = nullptr;
  ClusterTimeouts timeouts_;
  bool stopping_ = false;
  bool lost_ = false;
  std::atomic<std::int64_t> progress_ns_{0};  // 0: no run yet
  std::atomic<std::int64_t> checkpoint_at_{-1};
  std::atomic<bool> setup_begun_{false};
  // I/O thread only.
  std::string coordinator_;  // its routing id
  std::uint64_t run_ = 0;    // the run id of its hello (read by send() only after the hello)
  std::chrono::steady_clock::time_point heard_, beat_;
  std::optional<nlohmann::json> setup_;  // a set-up still waiting for parts of its model
  std::string model_;
  std::size_t model_expected_ = 0;
};

// The ZeroMQ transport of a worker's run (WorkerTransport): the exchange over the
// workers' data inboxes (`inbox`: this worker's, bound), results to the coordinator's
// results inbox, commands through io.
std::unique_ptr<WorkerTransport> zmq_worker_transport(zmq::context_t& ctx, zmq::socket_t& inbox, WorkerIo& io);

}  // namespace mbsflow
