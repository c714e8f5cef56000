#include "remote_exchange.hpp"

#include <algorithm>

#include "cluster_wire.hpp"
#include "mbsflow/graph/error.hpp"

namespace mbsflow {

RemoteExchange::RemoteExchange(zmq::context_t& ctx, const Decomposition& d, std::vector<partitioned::Part*> parts,
                               std::vector<int> worker_of, const std::vector<std::string>& worker_names,
                               const std::vector<std::string>& data_addresses, int stages, double send_timeout_s)
    : d_(d), parts_(std::move(parts)), worker_of_(std::move(worker_of)), worker_names_(worker_names), stages_(stages),
      outgoing_(d.submodels.size()) {
  // Remote submodel r takes the bodies e.from of its neighbour p: p sends them to r.
  for (std::size_t r = 0; r < d.submodels.size(); ++r) {
    if (parts_[r]) continue;
    for (const Submodel::Exchange& e : d.submodels[r].exchanges) {
      const auto p = static_cast<std::size_t>(e.neighbour);
      if (!parts_[p]) continue;
      const int w = worker_of_[r];
      auto [it, added] = senders_.try_emplace({static_cast<int>(p), w}, wire::make_socket(ctx, zmq::socket_type::push));
      if (added) {
        it->second.set(zmq::sockopt::sndtimeo, static_cast<int>(send_timeout_s * 1000.0));
        wire::connect(it->second, data_addresses[static_cast<std::size_t>(w)], "worker " + worker_names_[static_cast<std::size_t>(w)]);
      }
      outgoing_[p].push_back({static_cast<int>(r), &e.from, &it->second});
    }
  }
}

bool RemoteExchange::deliver(zmq::message_t& header, zmq::message_t& payload) {
  const auto h = wire::read_header<wire::ExchangeHeader>(header);
  const auto k = static_cast<int>(d_.submodels.size());
  if (!h || h->to < 0 || h->to >= k || h->from < 0 || h->from >= k || h->stage < 0 || h->stage >= stages_ ||
      !parts_[static_cast<std::size_t>(h->to)] || parts_[static_cast<std::size_t>(h->from)])
    return false;
  const Submodel& to = d_.submodels[static_cast<std::size_t>(h->to)];
  std::size_t bodies = 0;
  bool known = false;
  for (const Submodel::Exchange& e : to.exchanges)
    if (e.neighbour == h->from) bodies = e.from.size(), known = true;
  if (!known || payload.size() != bodies * partitioned::body_numbers * sizeof(double)) return false;
  std::function<void()> ready;
  {
    std::lock_guard lock(mutex_);
    const Slot slot{h->to, h->from, h->stage};
    inbox_[slot].push_back({h->step, std::move(payload)});
    auto w = waiting_.find({slot, h->step});
    if (w != waiting_.end()) {
      ready = std::move(w->second);
      waiting_.erase(w);
    }
  }
  if (ready) ready();
  return true;
}

void RemoteExchange::await(long n, int s, int q, int p, std::function<void()> ready) {
  if (n == 0 && s == 0) return ready();  // the initial state: every process has it
  {
    std::lock_guard lock(mutex_);
    const Slot slot{p, q, s};
    auto in = inbox_.find(slot);
    const bool here = in != inbox_.end() && std::any_of(in->second.begin(), in->second.end(),
                                                        [n](const Message& m) { return m.step == n; });
    if (!aborted_ && !here) {
      waiting_[{slot, n}] = std::move(ready);
      return;
    }
  }
  ready();
}

void RemoteExchange::receive(int p, long n, int s) {
  if (n == 0 && s == 0) return;
  partitioned::Part& me = *parts_[static_cast<std::size_t>(p)];
  for (const Submodel::Exchange& e : d_.submodels[static_cast<std::size_t>(p)].exchanges) {
    if (parts_[static_cast<std::size_t>(e.neighbour)]) continue;
    zmq::message_t m;
    {
      std::lock_guard lock(mutex_);
      auto& queue = inbox_[{p, e.neighbour, s}];
      if (queue.empty() || queue.front().step != n)
        throw RunError("boundary values of submodel " + std::to_string(e.neighbour) + " for step " + std::to_string(n) +
                       " stage " + std::to_string(s) + " are missing");
      m = std::move(queue.front().payload);
      queue.pop_front();
    }
    partitioned::unpack_bodies(me.system.layout(), me.x[static_cast<std::size_t>(s)], e.to, m.data());
  }
}

void RemoteExchange::send(int p, long n, int s) {
  const partitioned::Part& me = *parts_[static_cast<std::size_t>(p)];
  for (const Outgoing& o : outgoing_[static_cast<std::size_t>(p)]) {
    zmq::message_t payload(o.bodies->size() * partitioned::body_numbers * sizeof(double));
    partitioned::pack_bodies(me.system.layout(), me.x[static_cast<std::size_t>(s)], *o.bodies, payload.data());
    wire::ExchangeHeader h;
    h.from = p;
    h.to = o.to;
    h.stage = s;
    h.step = n;
    bool ok = false;
    try {
      ok = o.socket->send(zmq::const_buffer(&h, sizeof h), zmq::send_flags::sndmore).has_value() &&
           o.socket->send(payload, zmq::send_flags::none).has_value();
    } catch (const zmq::error_t&) {
    }
    if (!ok) {
      abort("cannot send boundary values to worker " +
            worker_names_[static_cast<std::size_t>(worker_of_[static_cast<std::size_t>(o.to)])] + " (it stopped taking them)");
      return;
    }
    ++sent_;
  }
}

void RemoteExchange::abort(const std::string& why) {
  std::map<std::pair<Slot, long>, std::function<void()>> waiting;
  {
    std::lock_guard lock(mutex_);
    if (aborted_) return;
    aborted_ = true;
    why_ = why;
    waiting.swap(waiting_);
  }
  for (auto& [slot, ready] : waiting) ready();
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
