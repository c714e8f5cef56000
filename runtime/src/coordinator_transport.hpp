#pragma once
// What the coordinator of a cluster run (coordinator.cpp) needs from the transport, with
// no transport type in sight: a control channel to each worker (JSON commands out, its
// replies in) and the results inbox every worker sends to. The ZeroMQ transport
// implements it (zmq_coordinator_transport.cpp), as worker_transport.hpp's interfaces are
// the workers' side.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "mbsflow/graph/state_layout.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "wire_format.hpp"

namespace mbsflow {

class CoordinatorTransport {
 public:
  virtual ~CoordinatorTransport() = default;
  // To worker w's control channel, without waiting: false where its queue is full (it has
  // taken nothing for long; the coordinator's heartbeat check reports it).
  virtual bool send(std::size_t w, const nlohmann::json& message) = 0;
  // A message and a part of text that travels with it, not copied: the text outlives the
  // transport.
  virtual bool send_with(std::size_t w, const nlohmann::json& message, std::string_view text) = 0;
  // Waits up to wait_s for anything to come in, then hands over all that did: the control
  // messages that parse (a JSON object with a string "type") to control(w, message), the
  // results of this run (a header of `run`'s, any worker number) to result(header,
  // payload). A payload lives until result() returns.
  virtual void poll(double wait_s, const std::function<void(std::size_t w, const nlohmann::json&)>& control,
                    const std::function<void(const wire::ResultHeader&, std::string_view payload)>& result) = 0;
  // Where the workers send their results.
  virtual const std::string& results_address() const = 0;
  // When the transport closes, worker w's messages still queued get up to `seconds` to go
  // out (else none: a lost worker's channel closes at once).
  virtual void linger(std::size_t w, double seconds) = 0;
};

// ZeroMQ: a DEALER to each worker's --listen endpoint, a PULL inbox bound at
// c.results_bind for results of up to the state's size, CURVE where `security` is given.
std::unique_ptr<CoordinatorTransport> make_zmq_coordinator_transport(const ClusterConfig& c, const StateLayout& state,
                                                                     const wire::Security* security, std::uint64_t run);

}  // namespace mbsflow
