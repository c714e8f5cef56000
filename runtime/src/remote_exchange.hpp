#pragma once
// A worker's side of the boundary exchange with submodels in other processes: one inbox
// (PULL) and one sender (PUSH) per local submodel and remote worker, used only by that
// submodel's stages, which the flow graph runs one after another. Messages name sender,
// receiver, step and stage; a received message waits in its slot until the receiving
// stage takes it, so none is dropped or taken for another stage. The inbox is read by
// whichever waiting proxy gets to it first (one at a time): no thread between the socket
// and the stage that needs the values. As a BoundaryExchange it also copies the ghosts
// whose owners run in this worker, and sums DOPRI5's error norm over every worker (each
// sends the squares of its own entries to all others, tagged with the stage number
// `stages`, and adds them all in global order).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>
#include <zmq.hpp>

#include "mbsflow/graph/decomposition.hpp"
#include "cluster_wire.hpp"
#include "partitioned_state.hpp"
#include "worker_transport.hpp"

namespace mbsflow {

class RemoteExchange final : public WorkerExchange {
 public:
  // parts[q]: local submodel q's state, null where q runs elsewhere; worker_of[q] its worker.
  RemoteExchange(zmq::context_t& ctx, zmq::socket_t& inbox, const Decomposition& d, std::vector<partitioned::Part*> parts,
                 std::vector<int> worker_of, const std::vector<std::string>& worker_names,
                 const std::vector<std::string>& data_addresses, int stages, double send_timeout_s, double delay_s,
                 std::uint64_t run, const wire::Security* security);
  ~RemoteExchange() override;
  // Marked (steady-clock ns) while wait() waits for peers: waiting is not a hung step.
  void set_progress_clock(std::atomic<std::int64_t>* clock) { progress_clock_ = clock; }

  // BoundaryExchange: local ghosts copied, remote ones received; values sent; the error
  // norm summed over every worker.
  void take(std::size_t p, long n, int s) override;
  void offer(std::size_t p, long n, int s) override { send(static_cast<int>(p), n, s); }
  double error_sum(long n, Eigen::VectorXd& squares) override;
  const std::vector<char>* local_submodels() const override { return &local_; }
  void fail(std::exception_ptr e) override;
  bool stopped() const override { return BoundaryExchange::stopped() || aborted(); }
  void check() const override;
  // From a proxy node: returns once remote q's values of stage input s of step n for local
  // p are in, or the exchange was aborted.
  void wait(long n, int s, int q, int p) override;

  // WorkerExchange (worker_transport.hpp). take_upto reads the inbox first unless another
  // thread does.
  void start_at(long n) override { start_step_ = n; }
  void receive(int p, long n, int s) override;
  void take_upto(int p, int q, int s, long cap, const std::function<void(long, const double*)>& take) override;
  void send(int p, long n, int s) override;
  void send(int p, long n, int s, const Eigen::VectorXd& x) override;
  void rewind(int s, long n) override;
  double max_over_workers(long n, double mine) override;
  void abort(const std::string& why) override;
  bool aborted() const override;
  std::string why() const override;
  long messages_sent() const override;
  double bytes_per_stage() const override;

 private:
  struct Message {
    long step;
    zmq::message_t payload;
  };
  struct Outgoing {
    int to;                  // remote submodel
    const std::vector<int>* bodies;  // local indices of the bodies it needs
    zmq::socket_t* socket;
  };
  using Slot = std::tuple<int, int, int>;  // to (local), from (remote), stage
  // Stores a two-frame message from the inbox; false if it is malformed.
  bool store(zmq::message_t& header, zmq::message_t& payload);
  // Sends one message, or queues it for the delayer; false if the exchange stopped.
  bool post(zmq::socket_t& socket, const wire::ExchangeHeader& h, zmq::message_t payload);
  // Sends `own` to every other worker as (stage, n) and gives each one's message of the
  // same (stage, n) to theirs(worker, numbers).
  void to_every_worker(long n, int stage, const std::vector<double>& own,
                       const std::function<void(std::size_t, const double*)>& theirs);
  // The first message of a slot, which must be of step n (RunError if it is not).
  zmq::message_t pop(const Slot& slot, long n, const std::string& what);
  // Waits up to `ms` for the inbox, then stores everything in it; false on a malformed message.
  bool read_inbox(int ms);
  // read_inbox as the one reading thread (reading_), with mutex_ held on entry and exit.
  void read_inbox_as_reader(std::unique_lock<std::mutex>& lock, int ms);

  zmq::context_t& ctx_;
  zmq::socket_t& inbox_socket_;
  std::vector<std::string> data_addresses_;
  double send_timeout_s_;

  const Decomposition& d_;
  std::vector<partitioned::Part*> parts_;
  std::vector<char> local_;  // per submodel: 1 if it runs here
  // The error-norm reduction: per worker its lowest submodel (the messages' sender and
  // receiver) and the global places of its submodels' own entries, in the order it sends them.
  std::vector<int> first_of_;
  std::vector<std::vector<Eigen::Index>> elements_of_;
  int me_ = -1;
  std::vector<int> worker_of_;
  std::vector<std::string> worker_names_;
  int stages_;
  std::map<std::pair<int, int>, zmq::socket_t> senders_;  // (local submodel, remote worker)
  std::vector<std::vector<Outgoing>> outgoing_;            // per local submodel

  mutable std::mutex mutex_;
  std::map<Slot, std::deque<Message>> inbox_;
  std::map<Slot, long> newest_;  // the latest step stored per slot
  std::condition_variable arrived_;
  bool aborted_ = false;
  bool reading_ = false;  // a thread is reading the inbox
  std::string why_;
  std::atomic<long> sent_{0};

  // With a delay (a slow network, for tests and the benchmark): messages wait in a queue
  // until they are due and a thread of their own sends them (then the only user of the
  // sockets).
  struct Delayed {
    std::chrono::steady_clock::time_point due;
    zmq::socket_t* socket;
    wire::ExchangeHeader header;
    zmq::message_t payload;
  };
  void deliver_delayed();
  // Sends one message now; stops the exchange, naming the receiving worker, if it cannot.
  bool transmit(zmq::socket_t& socket, const wire::ExchangeHeader& h, zmq::message_t& payload);
  void open_sender(zmq::socket_t& s, std::size_t worker);  // timeout, CURVE, connect to its inbox
  std::atomic<std::int64_t>* progress_clock_ = nullptr;
  long start_step_ = -1;  // see start_at
  std::uint64_t run_;  // the run id of every message sent and taken
  const wire::Security* security_;  // CURVE client keys for the other workers' inboxes, or null
  double delay_s_ = 0.0;
  std::mutex delay_mutex_;
  std::condition_variable delay_changed_;
  std::deque<Delayed> delayed_;
  bool stopping_ = false;
  std::thread delayer_;
};

}  // namespace mbsflow
