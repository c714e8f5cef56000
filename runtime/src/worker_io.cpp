#include "worker_io.hpp"

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "remote_exchange.hpp"

namespace mbsflow {

namespace {
std::atomic<int> io_count{0};  // distinct inproc names for several workers in one process (tests)
}

WorkerIo::WorkerIo(zmq::context_t& ctx, const std::string& listen)
    : ctx_(ctx), control_(wire::make_socket(ctx, zmq::socket_type::router)),
      wake_in_(wire::make_socket(ctx, zmq::socket_type::pair)), wake_out_(wire::make_socket(ctx, zmq::socket_type::pair)) {
  const std::string wake = "inproc://mbsflow-worker-io-" + std::to_string(io_count++);
  wake_in_.bind(wake);
  wake_out_.connect(wake);
  control_.set(zmq::sockopt::router_mandatory, 1);  // a reply to a vanished coordinator fails, never drops
  wire::bind(control_, listen, "the worker's control socket");
  endpoint_ = control_.get(zmq::sockopt::last_endpoint);
  thread_ = std::thread([this] { loop(); });
}

WorkerIo::~WorkerIo() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    wire::send(wake_out_, zmq::str_buffer("!"), zmq::send_flags::dontwait);
  }
  thread_.join();
}

std::optional<nlohmann::json> WorkerIo::next_command(double timeout_s) {
  std::unique_lock lock(mutex_);
  auto have = [&] { return !commands_.empty(); };
  if (timeout_s > 0.0) {
    if (!changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), have)) return std::nullopt;
  } else {
    changed_.wait(lock, have);
  }
  nlohmann::json j = std::move(commands_.front());
  commands_.pop_front();
  return j;
}

void WorkerIo::post_locked(std::function<void()> f) {
  posted_.push_back(std::move(f));
  wire::send(wake_out_, zmq::str_buffer("!"), zmq::send_flags::dontwait);  // under mutex_: one thread at a time
}

void WorkerIo::send(nlohmann::json message) {
  std::lock_guard lock(mutex_);
  post_locked([this, m = std::move(message)] {
    if (coordinator_.empty()) return;
    try {
      wire::send(control_, zmq::buffer(coordinator_), zmq::send_flags::sndmore);
      wire::send_json(control_, m);
    } catch (const zmq::error_t& e) {
      lose(std::string("the coordinator was lost: its connection is gone (") + e.what() + ")");
    }
  });
}

void WorkerIo::goodbye() {
  send({{"type", "bye"}});
  std::lock_guard lock(mutex_);
  post_locked([this] { control_.set(zmq::sockopt::linger, 1000); });
}

void WorkerIo::attach(RemoteExchange* exchange) {
  std::lock_guard lock(mutex_);
  exchange_ = exchange;
  if (exchange_ && lost_) exchange_->abort("the coordinator was lost");
}

ClusterTimeouts WorkerIo::timeouts() const {
  std::lock_guard lock(mutex_);
  return timeouts_;
}

// Called with mutex_ not held, on the I/O thread.
void WorkerIo::command(nlohmann::json j) {
  const std::string type = j.value("type", "");
  std::lock_guard lock(mutex_);
  if (type == "hello" && j.contains("timeouts")) {
    const auto& t = j["timeouts"];
    timeouts_ = {t.value("connect_s", 10.0), t.value("heartbeat_s", 0.5), t.value("lost_s", 3.0)};
  }
  if (type == "abort" && exchange_) exchange_->abort("stopped by the coordinator: " + j.value("reason", std::string()));
  commands_.push_back(std::move(j));
  changed_.notify_all();
}

void WorkerIo::lose(const std::string& why) {
  std::lock_guard lock(mutex_);
  if (lost_) return;
  lost_ = true;
  if (exchange_) exchange_->abort(why);
  commands_.push_back({{"type", "lost"}, {"reason", why}});
  changed_.notify_all();
}

void WorkerIo::loop() {
  using wire::Clock;
  heard_ = beat_ = Clock::now();
  while (true) {
    std::deque<std::function<void()>> todo;
    ClusterTimeouts t;
    bool lost, stopping;
    {
      std::lock_guard lock(mutex_);
      stopping = stopping_;
      todo.swap(posted_);
      t = timeouts_;
      lost = lost_;
    }
    for (auto& f : todo) f();  // what was posted before the stop still goes out (a goodbye)
    if (stopping) return;
    // Sleeps until a message, posted work (the wake-up socket) or the next heartbeat:
    // a thread that wakes for nothing would take a core from the compute.
    zmq::pollitem_t items[2] = {{control_.handle(), 0, ZMQ_POLLIN, 0}, {wake_in_.handle(), 0, ZMQ_POLLIN, 0}};
    const double until_beat = std::max(0.0, t.heartbeat_s - wire::seconds_since(beat_));
    wire::poll(items, 2, until_beat + 0.001);
    zmq::message_t ignored;
    while (wire::recv(wake_in_, ignored, zmq::recv_flags::dontwait)) {
    }
    if (items[0].revents & ZMQ_POLLIN) {
      zmq::message_t id, body;
      (void)wire::recv(control_, id);
      if (id.more()) (void)wire::recv(control_, body);
      const std::string from = id.to_string();
      nlohmann::json j = wire::parse_json(body);
      if (!j.is_object()) j = {{"type", "garbage"}};
      if (coordinator_.empty() && j.value("type", "") == "hello") coordinator_ = from;
      if (from != coordinator_) {
        // Another coordinator while this one is busy: tell it so, once.
        try {
          wire::send(control_, zmq::buffer(from), zmq::send_flags::sndmore);
          wire::send_json(control_, {{"type", "error"}, {"message", "this worker is busy with another run"}});
        } catch (const zmq::error_t&) {
        }
      } else {
        heard_ = Clock::now();
        if (j.value("type", "") != "heartbeat") command(std::move(j));
      }
    }
    if (!coordinator_.empty() && !lost) {
      if (wire::seconds_since(beat_) >= t.heartbeat_s) {
        beat_ = Clock::now();
        try {
          wire::send(control_, zmq::buffer(coordinator_), zmq::send_flags::sndmore);
          wire::send_json(control_, {{"type", "heartbeat"}});
        } catch (const zmq::error_t& e) {
          lose(std::string("the coordinator was lost: its connection is gone (") + e.what() + ")");
        }
      }
      if (wire::seconds_since(heard_) > t.lost_s) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "the coordinator was lost: nothing heard from it for %.1f s", t.lost_s);
        lose(buf);
      }
    }
  }
}

}  // namespace mbsflow
