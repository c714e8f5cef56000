#pragma once
// The ZeroMQ sockets between coordinator and workers, and their set-up both sides share;
// what they carry is in wire_format.hpp.
#include <chrono>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "random_id.hpp"
#include "wire_format.hpp"

namespace mbsflow::wire {

// A socket that never holds the process at close (linger 0) and takes no message larger
// than max_bytes.
zmq::socket_t make_socket(zmq::context_t& ctx, zmq::socket_type type, std::int64_t max_bytes = max_control_bytes);
// Before bind: a CURVE server whose clients the context's ZapGuard admits for `domain`.
void curve_server(zmq::socket_t& s, const Security* security, const char* domain);
// Before connect: a CURVE client of the server with public key server_key.
void curve_client(zmq::socket_t& s, const Security* security, const std::string& server_key);

// Binds; InputError naming what the endpoint is for when it cannot.
void bind(zmq::socket_t& s, const std::string& endpoint, const std::string& what);
void connect(zmq::socket_t& s, const std::string& endpoint, const std::string& what);
// The address peers use: `configured` if given, else the bound endpoint, which must not be a
// wildcard address.
std::string reachable_address(zmq::socket_t& bound, const std::string& configured, const std::string& what);

// zmq::poll that reports a signal (EINTR) as "nothing ready": the caller's loop then sees
// the stop request the signal handler set.
int poll(zmq::pollitem_t* items, std::size_t n, double seconds);

// recv and send that retry when a signal interrupts them (EINTR).
zmq::recv_result_t recv(zmq::socket_t& s, zmq::message_t& m, zmq::recv_flags flags = zmq::recv_flags::none);
zmq::send_result_t send(zmq::socket_t& s, zmq::const_buffer b, zmq::send_flags flags);
zmq::send_result_t send(zmq::socket_t& s, zmq::message_t& m, zmq::send_flags flags);

// JSON control messages.
// False when it would have to wait (the peer is gone or far behind).
bool send_json(zmq::socket_t& s, const nlohmann::json& j, zmq::send_flags flags = zmq::send_flags::dontwait);
// A control message: a JSON object with a string "type"; nullopt for anything else. With
// a run id, also nullopt unless the message carries that run's id ("run").
std::optional<nlohmann::json> parse_control(const zmq::message_t& m, std::optional<std::uint64_t> run = std::nullopt);
// Header frame + payload frame.
template <class Header>
bool send_framed(zmq::socket_t& s, const Header& h, const void* data, std::size_t bytes) {
  if (!send(s, zmq::const_buffer(&h, sizeof h), zmq::send_flags::sndmore)) return false;
  return send(s, zmq::const_buffer(data, bytes), zmq::send_flags::none).has_value();
}
// The header of a frame of run `run`; nullopt for anything else (size, magic, version,
// another run).
template <class Header>
std::optional<Header> read_header(const zmq::message_t& m, std::uint64_t run) {
  if (m.size() != sizeof(Header)) return std::nullopt;
  Header h;
  std::memcpy(&h, m.data(), sizeof h);
  if (h.magic != magic || h.version != frame_version || h.run != run) return std::nullopt;
  return h;
}

// Receives the rest of a multipart message that is being dropped.
void skip_rest(zmq::socket_t& s, const zmq::message_t& last);

}  // namespace mbsflow::wire
