#include "cluster_wire.hpp"

#include <cerrno>

#include "mbsflow/error.hpp"

namespace mbsflow::wire {

zmq::socket_t make_socket(zmq::context_t& ctx, zmq::socket_type type) {
  zmq::socket_t s(ctx, type);
  s.set(zmq::sockopt::linger, 0);
  return s;
}

void bind(zmq::socket_t& s, const std::string& endpoint, const std::string& what) {
  try {
    s.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw InputError("cannot bind " + what + " at " + endpoint + ": " + e.what());
  }
}

void connect(zmq::socket_t& s, const std::string& endpoint, const std::string& what) {
  try {
    s.connect(endpoint);
  } catch (const zmq::error_t& e) {
    throw InputError("cannot connect to " + what + " at " + endpoint + ": " + e.what());
  }
}

std::string reachable_address(zmq::socket_t& bound, const std::string& configured, const std::string& what) {
  if (!configured.empty()) return configured;
  const std::string got = bound.get(zmq::sockopt::last_endpoint);
  if (got.find("0.0.0.0") != std::string::npos || got.find("[::]") != std::string::npos)
    throw InputError(what + " binds every interface (" + got + "); give the address its peers use to reach it");
  return got;
}

int poll(zmq::pollitem_t* items, std::size_t n, double seconds) {
  try {
    return zmq::poll(items, n, std::chrono::milliseconds(static_cast<long>(seconds * 1000.0)));
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return 0;
    throw;
  }
}

namespace {
template <class F>
auto retrying(F f) {
  while (true) {
    try {
      return f();
    } catch (const zmq::error_t& e) {
      if (e.num() != EINTR) throw;
    }
  }
}
}  // namespace

zmq::recv_result_t recv(zmq::socket_t& s, zmq::message_t& m, zmq::recv_flags flags) {
  return retrying([&] { return s.recv(m, flags); });
}
zmq::send_result_t send(zmq::socket_t& s, zmq::const_buffer b, zmq::send_flags flags) {
  return retrying([&] { return s.send(b, flags); });
}
zmq::send_result_t send(zmq::socket_t& s, zmq::message_t& m, zmq::send_flags flags) {
  return retrying([&] { return s.send(m, flags); });
}

bool send_json(zmq::socket_t& s, const nlohmann::json& j, zmq::send_flags flags) {
  const std::string text = j.dump();
  return send(s, zmq::buffer(text), flags).has_value();
}

nlohmann::json parse_json(const zmq::message_t& m) {
  return nlohmann::json::parse(static_cast<const char*>(m.data()), static_cast<const char*>(m.data()) + m.size(),
                               nullptr, false);
}

}  // namespace mbsflow::wire
