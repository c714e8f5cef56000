#include "remote_exchange.hpp"

#include <algorithm>
#include <cstring>

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/dopri5.hpp"

namespace mbsflow {

RemoteExchange::RemoteExchange(zmq::context_t& ctx, zmq::socket_t& inbox, const Decomposition& d, std::vector<partitioned::Part*> parts,
                               std::vector<int> worker_of, const std::vector<std::string>& worker_names,
                               const std::vector<std::string>& data_addresses, int stages, double send_timeout_s,
                               double delay_s, std::uint64_t run, const wire::Security* security)
    : ctx_(ctx), inbox_socket_(inbox), data_addresses_(data_addresses), send_timeout_s_(send_timeout_s), d_(d), parts_(std::move(parts)), worker_of_(std::move(worker_of)), worker_names_(worker_names), stages_(stages),
      outgoing_(d.submodels.size()), run_(run), security_(security), delay_s_(delay_s) {
  const std::size_t workers = worker_names.size();
  first_of_.assign(workers, -1);
  elements_of_.resize(workers);
  for (std::size_t q = 0; q < d.submodels.size(); ++q) {
    local_.push_back(parts_[q] ? 1 : 0);
    const auto w = static_cast<std::size_t>(worker_of_[q]);
    if (parts_[q]) me_ = static_cast<int>(w);
    if (first_of_[w] < 0) first_of_[w] = static_cast<int>(q);
    const std::vector<Eigen::Index> e = partitioned::own_elements(d, q);
    elements_of_[w].insert(elements_of_[w].end(), e.begin(), e.end());
  }
  // Remote submodel r takes the bodies e.from of its neighbour p: p sends them to r.
  for (std::size_t r = 0; r < d.submodels.size(); ++r) {
    if (parts_[r]) continue;
    for (const Submodel::Exchange& e : d.submodels[r].exchanges) {
      const auto p = static_cast<std::size_t>(e.neighbour);
      if (!parts_[p]) continue;
      const int w = worker_of_[r];
      auto [it, added] = senders_.try_emplace({static_cast<int>(p), w}, wire::make_socket(ctx, zmq::socket_type::push));
      if (added) open_sender(it->second, static_cast<std::size_t>(w));
      outgoing_[p].push_back({static_cast<int>(r), &e.from, &it->second});
    }
  }
}

void RemoteExchange::open_sender(zmq::socket_t& s, std::size_t w) {
  s.set(zmq::sockopt::sndtimeo, static_cast<int>(send_timeout_s_ * 1000.0));
  if (security_) wire::curve_client(s, security_, security_->workers.at(w));
  wire::connect(s, data_addresses_[w], "worker " + worker_names_[w]);
}

RemoteExchange::~RemoteExchange() {
  if (!delayer_.joinable()) return;
  {
    std::lock_guard lock(delay_mutex_);
    stopping_ = true;
  }
  delay_changed_.notify_all();
  delayer_.join();
}

void RemoteExchange::deliver_delayed() {
  std::unique_lock lock(delay_mutex_);
  while (true) {
    delay_changed_.wait(lock, [&] { return stopping_ || !delayed_.empty(); });
    if (stopping_) return;
    const auto due = delayed_.front().due;
    if (std::chrono::steady_clock::now() < due) {
      delay_changed_.wait_until(lock, due);
      continue;
    }
    Delayed m = std::move(delayed_.front());
    delayed_.pop_front();
    lock.unlock();
    transmit(*m.socket, m.header, m.payload);
    lock.lock();
  }
}

bool RemoteExchange::store(zmq::message_t& header, zmq::message_t& payload) {
  const auto h = wire::read_header<wire::ExchangeHeader>(header, run_);
  const auto k = static_cast<int>(d_.submodels.size());
  if (!h || h->to < 0 || h->to >= k || h->from < 0 || h->from >= k || h->stage < 0 || h->stage > stages_ + 1 ||
      !parts_[static_cast<std::size_t>(h->to)] || parts_[static_cast<std::size_t>(h->from)])
    return false;
  if (h->stage >= stages_) {  // a worker's error squares or its one number, from its first submodel to ours
    const auto w = static_cast<std::size_t>(worker_of_[static_cast<std::size_t>(h->from)]);
    const std::size_t numbers = h->stage == stages_ ? elements_of_[w].size() : 1;
    if (h->from != first_of_[w] || h->to != first_of_[static_cast<std::size_t>(me_)] ||
        payload.size() != numbers * sizeof(double))
      return false;
  } else {
    const Submodel& to = d_.submodels[static_cast<std::size_t>(h->to)];
    std::size_t bodies = 0;
    bool known = false;
    for (const Submodel::Exchange& e : to.exchanges)
      if (e.neighbour == h->from) bodies = e.from.size(), known = true;
    if (!known || payload.size() != bodies * partitioned::body_numbers * sizeof(double)) return false;
  }
  std::lock_guard lock(mutex_);
  const Slot slot{h->to, h->from, h->stage};
  inbox_[slot].push_back({h->step, std::move(payload)});
  auto [it, added] = newest_.try_emplace(slot, h->step);
  if (!added) it->second = std::max(it->second, static_cast<long>(h->step));
  return true;
}

bool RemoteExchange::read_inbox(int ms) {
  zmq::pollitem_t item{inbox_socket_.handle(), 0, ZMQ_POLLIN, 0};
  if (wire::poll(&item, 1, ms / 1000.0) <= 0) return true;
  zmq::message_t header, payload;
  // A message that is not two frames of this run with the sizes the model gives is
  // dropped: whoever could send it, it cannot stop or corrupt the run.
  while (wire::recv(inbox_socket_, header, zmq::recv_flags::dontwait)) {
    if (!header.more()) continue;
    if (!wire::recv(inbox_socket_, payload)) return false;
    if (payload.more()) {
      wire::skip_rest(inbox_socket_, payload);
      continue;
    }
    (void)store(header, payload);
  }
  return true;
}

void RemoteExchange::wait(long n, int s, int q, int p) {
  if (n <= start_step_ && s == 0) return;
  std::unique_lock lock(mutex_);
  // Messages of a slot arrive in step order; taken ones may be gone from the queue.
  auto here = [&] {
    const auto it = newest_.find({p, q, s});
    return it != newest_.end() && it->second >= n;
  };
  while (!aborted_ && !here()) {
    if (progress_clock_) progress_clock_->store(wire::now_ns());
    if (reading_) {  // another proxy reads the inbox and tells when it has stored something
      arrived_.wait_for(lock, std::chrono::milliseconds(50));
      continue;
    }
    read_inbox_as_reader(lock, 50);  // short, so that an abort is seen in time
  }
}

void RemoteExchange::read_inbox_as_reader(std::unique_lock<std::mutex>& lock, int ms) {
  reading_ = true;
  lock.unlock();
  bool ok = false;
  try {
    ok = read_inbox(ms);
  } catch (const zmq::error_t&) {
  }
  lock.lock();
  reading_ = false;
  if (!ok && !aborted_) {
    aborted_ = true;
    why_ = "the inbox for boundary values failed";
  }
  arrived_.notify_all();
}

void RemoteExchange::receive(int p, long n, int s) {
  if (n <= start_step_ && s == 0) return;
  partitioned::Part& me = *parts_[static_cast<std::size_t>(p)];
  for (const Submodel::Exchange& e : d_.submodels[static_cast<std::size_t>(p)].exchanges) {
    if (parts_[static_cast<std::size_t>(e.neighbour)]) continue;
    const zmq::message_t m = pop({p, e.neighbour, s}, n, "boundary values of submodel " + std::to_string(e.neighbour));
    partitioned::unpack_bodies(me.system.layout(), me.input(s), e.to, m.data());
  }
}

zmq::message_t RemoteExchange::pop(const Slot& slot, long n, const std::string& what) {
  std::lock_guard lock(mutex_);
  auto& queue = inbox_[slot];
  if (queue.empty() || queue.front().step != n)
    throw RunError(what + " for step " + std::to_string(n) + " stage " + std::to_string(std::get<2>(slot)) +
                   " are missing");
  zmq::message_t m = std::move(queue.front().payload);
  queue.pop_front();
  return m;
}

void RemoteExchange::take(std::size_t p, long n, int s) {
  partitioned::copy_local_ghosts(parts_, p, s);
  receive(static_cast<int>(p), n, s);
}

void RemoteExchange::to_every_worker(long n, int stage, const std::vector<double>& own,
                                     const std::function<void(std::size_t, const double*)>& theirs) {
  const auto me = static_cast<std::size_t>(me_);
  const int mine = first_of_[me];
  for (std::size_t w = 0; w < first_of_.size(); ++w) {
    if (w == me || first_of_[w] < 0) continue;
    auto [it, added] = senders_.try_emplace({mine, static_cast<int>(w)}, wire::make_socket(ctx_, zmq::socket_type::push));
    if (added) open_sender(it->second, w);
    zmq::message_t payload(own.data(), own.size() * sizeof(double));
    wire::ExchangeHeader h;
    h.from = mine;
    h.to = first_of_[w];
    h.stage = stage;
    h.step = n;
    h.run = run_;
    if (!post(it->second, h, std::move(payload))) throw RunError(why());
  }
  for (std::size_t w = 0; w < first_of_.size(); ++w) {
    if (w == me || first_of_[w] < 0) continue;
    wait(n, stage, first_of_[w], mine);
    if (aborted()) throw RunError(why());
    const zmq::message_t m = pop({mine, first_of_[w], stage}, n, "the all-worker values of worker " + worker_names_[w]);
    std::vector<double> in(m.size() / sizeof(double));  // the message need not be aligned for doubles
    std::memcpy(in.data(), m.data(), in.size() * sizeof(double));
    theirs(w, in.data());
  }
}

double RemoteExchange::error_sum(long n, Eigen::VectorXd& squares) {
  const auto me = static_cast<std::size_t>(me_);
  std::vector<double> own(elements_of_[me].size());  // the same message for every other worker
  for (std::size_t i = 0; i < own.size(); ++i) own[i] = squares[elements_of_[me][i]];
  to_every_worker(n, stages_, own, [&](std::size_t w, const double* in) {
    for (const Eigen::Index e : elements_of_[w]) squares[e] = *in++;
  });
  return dopri5::ordered_sum(squares);
}

void RemoteExchange::rewind(int s, long n) {
  std::lock_guard lock(mutex_);
  for (auto& [slot, newest] : newest_) {
    if (std::get<2>(slot) != s) continue;
    const auto it = inbox_.find(slot);
    newest = it == inbox_.end() || it->second.empty() ? std::min(newest, n - 1) : it->second.back().step;
  }
}

double RemoteExchange::max_over_workers(long n, double mine) {
  double most = mine;
  to_every_worker(n, stages_ + 1, {mine}, [&](std::size_t, const double* in) { most = std::max(most, *in); });
  return most;
}

void RemoteExchange::fail(std::exception_ptr e) {
  BoundaryExchange::fail(e);
  try {
    std::rethrow_exception(e);
  } catch (const std::exception& x) {
    abort(error_text(x));
  } catch (...) {
    abort("a stage failed");
  }
}

void RemoteExchange::check() const {
  BoundaryExchange::check();
  if (aborted()) throw RunError(why());
}

void RemoteExchange::take_upto(int p, int q, int s, long cap, const std::function<void(long, const double*)>& take) {
  std::vector<Message> in;
  {
    std::unique_lock lock(mutex_);
    if (!reading_ && !aborted_) read_inbox_as_reader(lock, 0);
    auto& queue = inbox_[{p, q, s}];
    while (!queue.empty() && queue.front().step <= cap) {
      in.push_back(std::move(queue.front()));
      queue.pop_front();
    }
  }
  std::vector<double> values;  // aligned for doubles, which a message need not be
  for (const Message& m : in) {
    values.resize(m.payload.size() / sizeof(double));
    std::memcpy(values.data(), m.payload.data(), values.size() * sizeof(double));
    take(m.step, values.data());
  }
}

void RemoteExchange::send(int p, long n, int s) { send(p, n, s, parts_[static_cast<std::size_t>(p)]->input(s)); }

void RemoteExchange::send(int p, long n, int s, const Eigen::VectorXd& x) {
  const partitioned::Part& me = *parts_[static_cast<std::size_t>(p)];
  for (const Outgoing& o : outgoing_[static_cast<std::size_t>(p)]) {
    zmq::message_t payload(o.bodies->size() * partitioned::body_numbers * sizeof(double));
    partitioned::pack_bodies(me.system.layout(), x, *o.bodies, payload.data());
    wire::ExchangeHeader h;
    h.from = p;
    h.to = o.to;
    h.stage = s;
    h.step = n;
    h.run = run_;
    if (!post(*o.socket, h, std::move(payload))) return;
  }
}

bool RemoteExchange::post(zmq::socket_t& socket, const wire::ExchangeHeader& h, zmq::message_t payload) {
  if (delay_s_ > 0.0) {
    {
      std::lock_guard lock(delay_mutex_);
      if (!delayer_.joinable()) delayer_ = std::thread([this] { deliver_delayed(); });
      const auto due = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                               std::chrono::duration<double>(delay_s_));
      delayed_.push_back({due, &socket, h, std::move(payload)});
    }
    delay_changed_.notify_all();
    ++sent_;
    return true;
  }
  if (!transmit(socket, h, payload)) return false;
  ++sent_;
  return true;
}

bool RemoteExchange::transmit(zmq::socket_t& socket, const wire::ExchangeHeader& h, zmq::message_t& payload) {
  bool ok = false;
  try {
    ok = wire::send(socket, zmq::const_buffer(&h, sizeof h), zmq::send_flags::sndmore).has_value() &&
         wire::send(socket, payload, zmq::send_flags::none).has_value();
  } catch (const zmq::error_t&) {
  }
  if (!ok)
    abort("cannot send boundary values to worker " +
          worker_names_[static_cast<std::size_t>(worker_of_[static_cast<std::size_t>(h.to)])] + " (it stopped taking them)");
  return ok;
}

void RemoteExchange::abort(const std::string& why) {
  {
    std::lock_guard lock(mutex_);
    if (aborted_) return;
    aborted_ = true;
    why_ = why;
  }
  arrived_.notify_all();
}

bool RemoteExchange::aborted() const {
  std::lock_guard lock(mutex_);
  return aborted_;
}

std::string RemoteExchange::why() const {
  std::lock_guard lock(mutex_);
  return why_;
}

long RemoteExchange::messages_sent() const { return sent_.load(); }

double RemoteExchange::bytes_per_stage() const {
  double b = 0.0;
  for (const auto& list : outgoing_)
    for (const Outgoing& o : list) b += static_cast<double>(o.bodies->size() * partitioned::body_numbers * sizeof(double));
  return b;
}

}  // namespace mbsflow
