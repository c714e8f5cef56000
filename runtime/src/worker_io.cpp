#include "worker_io.hpp"

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {

namespace {
std::atomic<int> io_count{0};  // distinct inproc names for several workers in one process (tests)
}

WorkerIo::WorkerIo(zmq::context_t& ctx, const std::string& listen, const wire::Security* security)
    : ctx_(ctx), control_(wire::make_socket(ctx, zmq::socket_type::router)),
      wake_in_(wire::make_socket(ctx, zmq::socket_type::pair)), wake_out_(wire::make_socket(ctx, zmq::socket_type::pair)) {
  const std::string wake = "inproc://mbsflow-worker-io-" + std::to_string(io_count++);
  wake_in_.bind(wake);
  wake_out_.connect(wake);
  control_.set(zmq::sockopt::router_mandatory, 1);  // a reply to a vanished coordinator fails, never drops
  wire::curve_server(control_, security, "control");
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
      nlohmann::json with_run = m;
      with_run["run"] = id_text(run_);
      wire::send_json(control_, with_run);
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

void WorkerIo::attach(WorkerExchange* exchange) {
  std::lock_guard lock(mutex_);
  exchange_ = exchange;
  if (exchange_ && lost_) exchange_->abort("the coordinator was lost");
}

ClusterTimeouts WorkerIo::timeouts() const {
  std::lock_guard lock(mutex_);
  return timeouts_;
}

namespace {
// The timeouts of a hello, nullopt unless each is in its range and lost_s is more than
// twice heartbeat_s (a cluster file's rule): a coordinator cannot hold a worker forever.
std::optional<ClusterTimeouts> hello_timeouts(const nlohmann::json& hello) {
  const auto t = hello.find("timeouts");
  if (t == hello.end() || !t->is_object()) return std::nullopt;
  const auto connect = wire::number(*t, "connect_s", 1e-3, ClusterTimeouts::max_connect_s);
  const auto beat = wire::number(*t, "heartbeat_s", 1e-3, ClusterTimeouts::max_heartbeat_s);
  const auto lost = wire::number(*t, "lost_s", 1e-3, ClusterTimeouts::max_lost_s);
  if (!connect || !beat || !lost || !(*lost > 2.0 * *beat)) return std::nullopt;
  return ClusterTimeouts{*connect, *beat, *lost};
}
}  // namespace

// Called with mutex_ not held, on the I/O thread; j is a valid control message.
void WorkerIo::command(nlohmann::json j) {
  const std::string type = wire::text(j, "type");
  if (type == "checkpoint") {  // the run loop looks at it between steps
    if (const auto at = wire::number(j, "at", 0.0, 1e15)) checkpoint_at_ = static_cast<std::int64_t>(*at);
    return;
  }
  std::lock_guard lock(mutex_);
  if (type == "abort" && exchange_) exchange_->abort("stopped by the coordinator: " + wire::text(j, "reason"));
  commands_.push_back(std::move(j));
  changed_.notify_all();
}

void WorkerIo::begin_setup(nlohmann::json j) {
  const auto bytes = wire::number(j, "model_bytes", 0.0, static_cast<double>(wire::max_model_bytes));
  if (!bytes) return command(std::move(j));  // the main thread refuses it: no model
  setup_ = std::move(j);
  setup_begun_ = true;
  model_expected_ = static_cast<std::size_t>(*bytes);
  model_.clear();
  // Memory grows with what arrives, never with what was announced: a set-up announcing
  // 2^38 bytes costs nothing until the bytes come (and they are capped per part).
  model_.shrink_to_fit();
  take_model_part(zmq::message_t());
}

void WorkerIo::take_model_part(const zmq::message_t& part) {
  if (!setup_) return;  // a part without a set-up before it
  if (part.size() > model_expected_ - model_.size()) return lose("the set-up's model came longer than announced");
  model_.append(static_cast<const char*>(part.data()), part.size());
  if (model_.size() < model_expected_) return;
  (*setup_)["model"] = std::move(model_);
  command(std::move(*setup_));
  setup_.reset();
  model_ = std::string();
}

void WorkerIo::lose(const std::string& why) {
  std::lock_guard lock(mutex_);
  if (lost_) return;
  lost_ = true;
  if (exchange_) exchange_->abort(why);
  commands_.push_back({{"type", "lost"}, {"reason", why}});
  changed_.notify_all();
}

void WorkerIo::reply_error(const std::string& to, const std::string& message) {
  try {
    wire::send(control_, zmq::buffer(to), zmq::send_flags::sndmore);
    wire::send_json(control_, {{"type", "error"}, {"message", message}});
  } catch (const zmq::error_t&) {
  }
}

// One message of the control socket. Its sender is known before a byte of it is parsed:
// after the hello only the coordinator's messages are read (another peer gets a refusal,
// unread); before it only a message small enough to be a hello is parsed, so that an
// unknown peer cannot make this worker spend memory on a large one.
void WorkerIo::receive() {
  zmq::message_t id, body, attachment;
  (void)wire::recv(control_, id);
  if (id.more()) (void)wire::recv(control_, body);
  if (body.more()) (void)wire::recv(control_, attachment);
  wire::skip_rest(control_, attachment);
  const std::string from = id.to_string();
  if (!coordinator_.empty() && from != coordinator_) {
    reply_error(from, "this worker is busy with another run");
    return;
  }
  if (coordinator_.empty()) {
    if (body.size() > max_hello_bytes) return;
    const std::optional<nlohmann::json> j = wire::parse_control(body, std::nullopt);
    if (!j || wire::text(*j, "type") != "hello") return;
    const std::string run = wire::text(*j, "run");
    const auto t = hello_timeouts(*j);
    if (run.size() != 16 || run.find_first_not_of("0123456789abcdef") != std::string::npos || !t)
      return reply_error(from, "refused a hello without a run id or with timeouts out of range");
    coordinator_ = from;
    run_ = std::stoull(run, nullptr, 16);
    {
      std::lock_guard lock(mutex_);
      timeouts_ = *t;
    }
    heard_ = wire::Clock::now();
    return command(*j);
  }
  std::optional<nlohmann::json> j = wire::parse_control(body, run_);
  if (!j) return;  // not of this run, or no control message
  heard_ = wire::Clock::now();
  const std::string type = wire::text(*j, "type");
  if (type == "setup")
    begin_setup(std::move(*j));
  else if (type == "model_part")
    take_model_part(attachment);
  else if (type != "heartbeat")
    command(std::move(*j));
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
      // Whatever a message holds, it ends in a refusal or a named loss of the coordinator,
      // never in an exception that leaves this thread (and aborts the process).
      try {
        receive();
      } catch (const std::bad_alloc&) {
        lose("the coordinator's message does not fit in this worker's memory");
      } catch (const std::exception& e) {
        lose(std::string("a message from the coordinator could not be taken: ") + e.what());
      }
    }
    if (!coordinator_.empty() && !lost) {
      if (wire::seconds_since(beat_) >= t.heartbeat_s) {
        beat_ = Clock::now();
        try {
          wire::send(control_, zmq::buffer(coordinator_), zmq::send_flags::sndmore);
          nlohmann::json beat = {{"type", "heartbeat"}, {"run", id_text(run_)}};
          if (const std::int64_t p = progress_ns_.load(); p > 0) beat["stalled_s"] = 1e-9 * static_cast<double>(wire::now_ns() - p);
          wire::send_json(control_, beat);
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
