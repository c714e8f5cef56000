#pragma once
// What goes over the wire between coordinator and workers, without the sockets: the
// binary headers, the size caps, the keys of a secured run and the helpers that read
// control messages. Control messages are JSON; boundary values and snapshots are a small
// binary header frame followed by a frame of doubles (all hosts must share the byte order
// and double format; the magic number catches a mismatch). cluster_wire.hpp adds the
// ZeroMQ sockets that carry them.
#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mbsflow/graph/state_layout.hpp"
#include "mbsflow/runtime/curve_keys.hpp"

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
// Boundary values and snapshots of a model whose state has this layout; coupling records of a run.
std::int64_t max_data_bytes(const StateLayout& state);

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

// CURVE for the sockets of one process of a run: its own pair and the peers' public keys
// (a worker connects to the coordinator's results inbox and to other workers' inboxes as a
// client that must know the server's key). Null where a run is insecure.
struct Security {
  CurveKeyPair mine;
  std::string coordinator;           // public key
  std::vector<std::string> workers;  // public keys, by worker number
};
// True for ipc and for tcp on 127.x.x.x, localhost or [::1].
bool loopback(const std::string& endpoint);
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

// Bytes as lowercase hex (a resumed run's state in the set-up's JSON) and back; nullopt
// for anything but an even number of hex digits.
std::string hex(const std::vector<std::uint8_t>& bytes);
std::optional<std::vector<std::uint8_t>> unhex(const std::string& text);

}  // namespace mbsflow::wire
