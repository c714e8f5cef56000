#include "zap_guard.hpp"

#include <array>

#include "cluster_wire.hpp"

namespace mbsflow {

ZapGuard::ZapGuard(zmq::context_t& ctx, std::function<void(const std::string&)> log)
    : socket_(wire::make_socket(ctx, zmq::socket_type::rep, 4096)), log_(std::move(log)) {
  socket_.bind("inproc://zeromq.zap.01");  // the address libzmq asks (RFC 27)
  thread_ = std::thread([this] { loop(); });
}

ZapGuard::~ZapGuard() {
  stopping_ = true;
  thread_.join();
}

void ZapGuard::allow(const std::string& domain, const std::string& z85_key) {
  std::lock_guard lock(mutex_);
  allowed_[domain].insert(z85_key);
}

void ZapGuard::loop() {
  while (!stopping_) {
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    if (wire::poll(&item, 1, 0.1) <= 0) continue;
    // version, request id, domain, address, identity, mechanism, credentials...
    std::array<zmq::message_t, 7> f;
    std::size_t n = 0;
    bool more = true;
    while (more) {
      zmq::message_t part;
      if (!wire::recv(socket_, part)) break;
      more = part.more();
      if (n < f.size()) f[n++] = std::move(part);
    }
    const std::string domain = f[2].to_string(), address = f[3].to_string(), mechanism = f[5].to_string();
    std::string key;
    if (mechanism == "CURVE" && f[6].size() == 32) {
      char z85[41];
      zmq_z85_encode(z85, static_cast<const std::uint8_t*>(f[6].data()), 32);
      key = z85;
    }
    bool ok = false;
    {
      std::lock_guard lock(mutex_);
      const auto it = allowed_.find(domain);
      ok = n == f.size() && f[0].to_string() == "1.0" && !key.empty() && it != allowed_.end() && it->second.count(key) > 0;
    }
    if (!ok) {
      ++refused_;
      if (log_) log_("refused a " + (mechanism.empty() ? std::string("?") : mechanism) + " client at " + address + " on " +
                     (domain.empty() ? "?" : domain) + (key.empty() ? ": no key" : ": key " + key + " is not in the cluster file"));
    }
    const std::string status = ok ? "200" : "400";
    const std::string text = ok ? "OK" : "not admitted";
    wire::send(socket_, zmq::str_buffer("1.0"), zmq::send_flags::sndmore);
    wire::send(socket_, zmq::const_buffer(f[1].data(), f[1].size()), zmq::send_flags::sndmore);
    wire::send(socket_, zmq::buffer(status), zmq::send_flags::sndmore);
    wire::send(socket_, zmq::buffer(text), zmq::send_flags::sndmore);
    wire::send(socket_, zmq::buffer(key), zmq::send_flags::sndmore);  // user id
    wire::send(socket_, zmq::const_buffer(nullptr, 0), zmq::send_flags::none);  // metadata
  }
}

}  // namespace mbsflow
