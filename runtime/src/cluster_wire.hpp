#pragma once
// What goes over the wire between coordinator and workers, and the ZeroMQ socket set-up
// both sides share. Control messages are JSON; boundary values and snapshots are a small
// binary header frame followed by a frame of doubles (all hosts must share the byte order
// and double format; the magic number catches a mismatch).
#include <chrono>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <zmq.hpp>

namespace mbsflow::wire {

constexpr std::uint32_t magic = 0x4d42'5346;  // "MBSF"

// Boundary values of submodel `from` for stage input `stage` of step `step`, for `to`.
struct ExchangeHeader {
  std::uint32_t magic = wire::magic;
  std::int32_t from = 0, to = 0, stage = 0;
  std::int64_t step = 0;
};

// A dense snapshot (DOPRI5's dense output between steps) still needs the drivers imposed
// and the orientations renormalised, which the coordinator does on the whole state.
enum class ResultKind : std::uint32_t { snapshot = 1, progress = 2, done = 3, failed = 4, coupling = 5, dense = 6 };
// A coupling message carries rows of (index, t_start, t_end, position error, velocity
// error, lag) of CouplingRecord.
constexpr std::size_t coupling_row = 6;

// Worker -> coordinator on the results channel; a snapshot carries the own bodies of the
// worker's submodels (ascending), a failure its message, done the counts of done_counts.
struct ResultHeader {
  std::uint32_t magic = wire::magic;
  ResultKind kind = ResultKind::progress;
  std::int32_t worker = 0;
  std::int32_t pad = 0;
  std::int64_t step = 0;   // steps completed
  std::int64_t index = 0;  // a snapshot's number: they complete in increasing order
  double t = 0.0;          // model time reached, or of the snapshot
};
// Boundary messages sent, boundary bytes per stage, right-hand side evaluations, steps,
// rejected steps.
constexpr std::size_t done_counts = 5;

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A socket that never holds the process at close (linger 0).
zmq::socket_t make_socket(zmq::context_t& ctx, zmq::socket_type type);
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
nlohmann::json parse_json(const zmq::message_t& m);

// Header frame + payload frame.
template <class Header>
bool send_framed(zmq::socket_t& s, const Header& h, const void* data, std::size_t bytes) {
  if (!send(s, zmq::const_buffer(&h, sizeof h), zmq::send_flags::sndmore)) return false;
  return send(s, zmq::const_buffer(data, bytes), zmq::send_flags::none).has_value();
}
template <class Header>
std::optional<Header> read_header(const zmq::message_t& m) {
  if (m.size() != sizeof(Header)) return std::nullopt;
  Header h;
  std::memcpy(&h, m.data(), sizeof h);
  if (h.magic != magic) return std::nullopt;
  return h;
}

}  // namespace mbsflow::wire
