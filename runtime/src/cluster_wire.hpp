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
#include <vector>
#include <zmq.hpp>

#include "mbsflow/runtime/curve_keys.hpp"
#include "random_id.hpp"

namespace mbsflow::wire {

constexpr std::uint32_t magic = 0x4d42'5346;  // "MBSF"
constexpr std::uint32_t frame_version = 2;     // of the binary headers below; 2: run ids

// Every message of a run carries its run id, which the coordinator draws at random
// (random_id.hpp) and sends in its hello, as id_text: a message of another run
// (replayed, or a late one of a run that ended) is dropped.

// The size caps of messages: ZeroMQ drops a peer whose message is larger before it is
// received (ZMQ_MAXMSGSIZE). Control messages carry the set-up (the assignment of
// every body) and the model's text in parts of model_part_bytes.
constexpr std::int64_t max_control_bytes = (std::int64_t{1} << 30) + (std::int64_t{16} << 20);
// A part small enough to be copied, encrypted and taken apart in a fraction of a second,
// so that heartbeats go on between the parts: the 450 MB text of a million bodies in one
// frame held the I/O of both sides for seconds (page faults), and the peers lost each other.
constexpr std::size_t model_part_bytes = std::size_t{8} << 20;
// The longest model text a worker takes.
constexpr std::uint64_t max_model_bytes = std::uint64_t{1} << 38;
// Boundary values and snapshots of a model of `bodies` bodies; coupling records of a run.
std::int64_t max_data_bytes(std::size_t bodies);

// Boundary values of submodel `from` for stage input `stage` of step `step`, for `to`.
struct ExchangeHeader {
  std::uint32_t magic = wire::magic;
  std::uint32_t version = frame_version;
  std::int32_t from = 0, to = 0, stage = 0, pad = 0;
  std::int64_t step = 0;
  std::uint64_t run = 0;
};

// A dense snapshot (DOPRI5's dense output between steps) still needs the drivers imposed
// and the orientations renormalised, which the coordinator does on the whole state.
// A checkpoint (cluster.hpp) carries the worker's state at checkpoint opportunity `index`
// for the request in `step`, or nothing when the worker was past it (`index`: where it is).
enum class ResultKind : std::uint32_t { snapshot = 1, progress = 2, done = 3, failed = 4, coupling = 5, dense = 6, checkpoint = 7 };
// A coupling message carries rows of (index, t_start, t_end, position error, velocity
// error, lag) of CouplingRecord.
constexpr std::size_t coupling_row = 6;

// Worker -> coordinator on the results channel; a snapshot carries the own bodies of the
// worker's submodels (ascending), a failure its message, done the counts of done_counts.
struct ResultHeader {
  std::uint32_t magic = wire::magic;
  ResultKind kind = ResultKind::progress;
  std::int32_t worker = 0;
  std::uint32_t version = frame_version;
  std::uint64_t run = 0;
  std::int64_t step = 0;   // steps completed
  std::int64_t index = 0;  // a snapshot's number: they complete in increasing order
  double t = 0.0;          // model time reached, or of the snapshot
};
// Boundary messages sent, boundary bytes per stage, right-hand side evaluations, steps,
// rejected steps.
constexpr std::size_t done_counts = 5;

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
// Now in ns of the steady clock: a time one thread stores in an atomic for another.
inline std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

// A socket that never holds the process at close (linger 0) and takes no message larger
// than max_bytes.
zmq::socket_t make_socket(zmq::context_t& ctx, zmq::socket_type type, std::int64_t max_bytes = max_control_bytes);
// CURVE for the sockets of one process of a run: its own pair and the peers' public keys
// (a worker connects to the coordinator's results inbox and to other workers' inboxes as a
// client that must know the server's key). Null where a run is insecure.
struct Security {
  CurveKeyPair mine;
  std::string coordinator;           // public key
  std::vector<std::string> workers;  // public keys, by worker number
};
// Before bind: a CURVE server whose clients the context's ZapGuard admits for `domain`.
void curve_server(zmq::socket_t& s, const Security* security, const char* domain);
// Before connect: a CURVE client of the server with public key server_key.
void curve_client(zmq::socket_t& s, const Security* security, const std::string& server_key);
// True for ipc and for tcp on 127.x.x.x, localhost or [::1].
bool loopback(const std::string& endpoint);

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
// An upper bound of the memory a parse of text takes (its text and its values): a
// message whose bound is over max_parse_factor times its size, plus 64 MiB, is not parsed.
std::size_t parsed_bytes_bound(std::string_view text);
constexpr std::size_t max_parse_factor = 8;
// A long list of integers as one JSON string ("0,0,1,..."), which costs its size to parse;
// and back: nullopt unless every item is an integer in [lo, hi].
std::string integer_list_text(const std::vector<int>& v);
std::optional<std::vector<int>> integer_list(std::string_view text, int lo, int hi);
// Fields of a control message that may be anything: a string (else `otherwise`), a
// number in [lo, hi] (else nullopt).
std::string text(const nlohmann::json& j, const char* key, const std::string& otherwise = "");
std::optional<double> number(const nlohmann::json& j, const char* key, double lo, double hi);

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

// Bytes as lowercase hex (a resumed run's state in the set-up's JSON) and back; nullopt
// for anything but an even number of hex digits.
std::string hex(const std::vector<std::uint8_t>& bytes);
std::optional<std::vector<std::uint8_t>> unhex(const std::string& text);

// Receives the rest of a multipart message that is being dropped.
void skip_rest(zmq::socket_t& s, const zmq::message_t& last);

}  // namespace mbsflow::wire
