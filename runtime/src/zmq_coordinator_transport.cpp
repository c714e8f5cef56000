// The coordinator's side of the ZeroMQ transport (coordinator_transport.hpp).
#include <cstdio>
#include <optional>
#include <vector>

#include "cluster_wire.hpp"
#include "coordinator_transport.hpp"
#include "zap_guard.hpp"

namespace mbsflow {
namespace {

class ZmqCoordinatorTransport final : public CoordinatorTransport {
 public:
  ZmqCoordinatorTransport(const ClusterConfig& c, const StateLayout& state, const wire::Security* security, std::uint64_t run)
      : run_(run), results_(wire::make_socket(ctx_, zmq::socket_type::pull, wire::max_data_bytes(state))) {
    if (security) {
      zap_.emplace(ctx_, [](const std::string& line) { std::fprintf(stderr, "mbsflow coordinator: %s\n", line.c_str()); });
      for (const ClusterWorker& w : c.workers) zap_->allow("results", w.public_key);
    }
    wire::curve_server(results_, security, "results");
    wire::bind(results_, c.results_bind, "the coordinator's results inbox");
    results_address_ = wire::reachable_address(results_, c.results_address, "the coordinator's results inbox " + c.results_bind);
    for (const ClusterWorker& w : c.workers) {
      control_.push_back(wire::make_socket(ctx_, zmq::socket_type::dealer));
      wire::curve_client(control_.back(), security, w.public_key);
      wire::connect(control_.back(), w.address, "worker " + w.name);
    }
  }

  bool send(std::size_t w, const nlohmann::json& message) override { return wire::send_json(control_[w], message); }

  bool send_with(std::size_t w, const nlohmann::json& message, std::string_view text) override {
    zmq::message_t part(const_cast<char*>(text.data()), text.size(), nullptr);  // no free: not ours
    return wire::send_json(control_[w], message, zmq::send_flags::sndmore | zmq::send_flags::dontwait) &&
           wire::send(control_[w], part, zmq::send_flags::dontwait);
  }

  void poll(double wait_s, const std::function<void(std::size_t, const nlohmann::json&)>& control,
            const std::function<void(const wire::ResultHeader&, std::string_view)>& result) override {
    std::vector<zmq::pollitem_t> items;
    for (zmq::socket_t& s : control_) items.push_back({s.handle(), 0, ZMQ_POLLIN, 0});
    items.push_back({results_.handle(), 0, ZMQ_POLLIN, 0});
    wire::poll(items.data(), items.size(), wait_s);
    for (std::size_t w = 0; w < control_.size(); ++w) {
      if (!(items[w].revents & ZMQ_POLLIN)) continue;
      zmq::message_t m;
      while (wire::recv(control_[w], m, zmq::recv_flags::dontwait))
        if (const auto j = wire::parse_control(m)) control(w, *j);
    }
    if (items.back().revents & ZMQ_POLLIN) {
      zmq::message_t header, payload;
      while (wire::recv(results_, header, zmq::recv_flags::dontwait)) {
        payload = zmq::message_t();
        if (header.more()) (void)wire::recv(results_, payload);
        wire::skip_rest(results_, payload);
        // Anything but a result of this run is dropped: a stray or forged frame can
        // neither end nor stop the run.
        if (const auto h = wire::read_header<wire::ResultHeader>(header, run_))
          result(*h, {static_cast<const char*>(payload.data()), payload.size()});
      }
    }
  }

  const std::string& results_address() const override { return results_address_; }

  void linger(std::size_t w, double seconds) override {
    control_[w].set(zmq::sockopt::linger, static_cast<int>(seconds * 1000.0));
  }

 private:
  std::uint64_t run_;
  zmq::context_t ctx_;
  std::optional<ZapGuard> zap_;  // before the sockets: it outlives them
  zmq::socket_t results_;
  std::string results_address_;
  std::vector<zmq::socket_t> control_;  // DEALER connected to each worker's --listen endpoint
};

}  // namespace

std::unique_ptr<CoordinatorTransport> make_zmq_coordinator_transport(const ClusterConfig& c, const StateLayout& state,
                                                                     const wire::Security* security, std::uint64_t run) {
  return std::make_unique<ZmqCoordinatorTransport>(c, state, security, run);
}

}  // namespace mbsflow
