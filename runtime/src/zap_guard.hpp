#pragma once
// The ZAP handler of a ZeroMQ context: every CURVE server socket of the context (zap
// domain "control", "data" or "results") asks it whether a client's public key may
// connect, and it admits only the keys allowed for that domain. Without a handler a CURVE
// server admits any client, so one runs for as long as the context's sockets do.
#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <zmq.hpp>

namespace mbsflow {

class ZapGuard {
 public:
  // log: told of every refused client (domain, its address and key).
  ZapGuard(zmq::context_t& ctx, std::function<void(const std::string&)> log);
  ~ZapGuard();
  ZapGuard(const ZapGuard&) = delete;
  ZapGuard& operator=(const ZapGuard&) = delete;

  void allow(const std::string& domain, const std::string& z85_key);
  long refused() const { return refused_; }

 private:
  void loop();
  zmq::socket_t socket_;
  std::function<void(const std::string&)> log_;
  std::mutex mutex_;
  std::map<std::string, std::set<std::string>> allowed_;  // domain -> Z85 keys
  std::atomic<bool> stopping_{false};
  std::atomic<long> refused_{0};
  std::thread thread_;
};

}  // namespace mbsflow
