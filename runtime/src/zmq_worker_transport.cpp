// The ZeroMQ transport of a worker's run: RemoteExchange over the workers' data inboxes,
// a PUSH socket to the coordinator's results inbox, the commands through WorkerIo.
#include <zmq.hpp>

#include "cluster_wire.hpp"
#include "remote_exchange.hpp"
#include "worker_io.hpp"
#include "worker_part.hpp"

namespace mbsflow {

namespace {

class ZmqResults final : public ResultsChannel {
 public:
  ZmqResults(zmq::context_t& ctx, const Session& s, double timeout_s) : socket_(wire::make_socket(ctx, zmq::socket_type::push)) {
    socket_.set(zmq::sockopt::sndtimeo, static_cast<int>(timeout_s * 1000.0));
    if (s.security) wire::curve_client(socket_, &*s.security, s.security->coordinator);
    wire::connect(socket_, s.results_address, "the coordinator's results inbox");
  }
  bool send(const wire::ResultHeader& h, const void* data, std::size_t bytes) override {
    try {
      return wire::send_framed(socket_, h, data, bytes);
    } catch (const zmq::error_t&) {
      return false;
    }
  }

 private:
  zmq::socket_t socket_;
};

class ZmqWorkerTransport final : public WorkerTransport {
 public:
  ZmqWorkerTransport(zmq::context_t& ctx, zmq::socket_t& inbox, WorkerIo& io) : ctx_(ctx), inbox_(inbox), io_(io) {}
  WorkerControl& control() override { return io_; }
  std::unique_ptr<WorkerExchange> exchange(const Session& s, const nlohmann::json& start, std::vector<partitioned::Part*> parts,
                                           int stages) override {
    auto e = std::make_unique<RemoteExchange>(
        ctx_, inbox_, s.d, std::move(parts), s.worker_of, start.at("names").get<std::vector<std::string>>(),
        start.at("data_addresses").get<std::vector<std::string>>(), stages, io_.timeouts().lost_s, s.exchange_delay_s, s.run,
        s.security ? &*s.security : nullptr);
    e->set_progress_clock(io_.progress_clock());
    return e;
  }
  std::unique_ptr<ResultsChannel> results(const Session& s) override {
    return std::make_unique<ZmqResults>(ctx_, s, io_.timeouts().lost_s);
  }

 private:
  zmq::context_t& ctx_;
  zmq::socket_t& inbox_;
  WorkerIo& io_;
};

}  // namespace

std::unique_ptr<WorkerTransport> zmq_worker_transport(zmq::context_t& ctx, zmq::socket_t& inbox, WorkerIo& io) {
  return std::make_unique<ZmqWorkerTransport>(ctx, inbox, io);
}

}  // namespace mbsflow
