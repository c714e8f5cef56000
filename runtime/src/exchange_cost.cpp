// Measuring what one boundary message costs (for mbsflow bench cluster).
#include <algorithm>
#include <filesystem>
#include <thread>
#include <unistd.h>

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/line_fit.hpp"
#include "exchange_cost.hpp"

namespace mbsflow {
namespace {

// A message within `seconds`, or false.
bool receive_within(zmq::socket_t& s, zmq::message_t& m, double seconds) {
  const auto start = wire::Clock::now();
  while (!wire::recv(s, m, zmq::recv_flags::dontwait)) {
    const double left = seconds - wire::seconds_since(start);
    if (left <= 0.0) return false;
    zmq::pollitem_t item{s.handle(), 0, ZMQ_POLLIN, 0};
    wire::poll(&item, 1, left);
  }
  return true;
}

}  // namespace

std::vector<ExchangeSample> measure_exchange(const std::string& transport, const std::vector<std::size_t>& sizes,
                                             int round_trips) {
  zmq::context_t ctx;
  const std::string dir = (std::filesystem::temp_directory_path() / ("mbsflow-ping-" + std::to_string(::getpid()))).string();
  if (transport == "ipc") std::filesystem::create_directories(dir);
  auto endpoint = [&](const char* name) { return transport == "ipc" ? "ipc://" + dir + "/" + name : std::string("tcp://127.0.0.1:*"); };
  zmq::socket_t here_in = wire::make_socket(ctx, zmq::socket_type::pull), there_in = wire::make_socket(ctx, zmq::socket_type::pull);
  wire::bind(here_in, endpoint("a"), "the ping inbox");
  wire::bind(there_in, endpoint("b"), "the echo inbox");
  const std::string here = here_in.get(zmq::sockopt::last_endpoint), there = there_in.get(zmq::sockopt::last_endpoint);
  const long total = static_cast<long>(sizes.size()) * (round_trips + 10);
  // The echo side: sends every message back. Its socket lingers (bounded) when it closes:
  // with make_socket's linger 0 the last reply could still be queued and be dropped, and
  // the ping side would wait for it.
  std::thread echo([&ctx, &there_in, here, total] {
    zmq::socket_t out = wire::make_socket(ctx, zmq::socket_type::push);
    out.set(zmq::sockopt::linger, 5000);
    out.connect(here);
    for (long i = 0; i < total; ++i) {
      zmq::message_t m;
      if (!receive_within(there_in, m, 10.0)) return;
      out.send(m, zmq::send_flags::none);
    }
  });
  zmq::socket_t out = wire::make_socket(ctx, zmq::socket_type::push);
  out.connect(there);
  std::vector<ExchangeSample> result;
  bool lost = false;
  for (std::size_t bytes : sizes) {
    std::vector<double> times;
    for (int i = 0; i < round_trips + 10 && !lost; ++i) {  // the first 10 warm up
      zmq::message_t m(bytes), back;
      const auto start = wire::Clock::now();
      out.send(m, zmq::send_flags::none);
      lost = !receive_within(here_in, back, 10.0);  // a lost message must not hang the benchmark
      if (i >= 10) times.push_back(wire::seconds_since(start) / 2.0);
    }
    if (lost) break;
    std::nth_element(times.begin(), times.begin() + static_cast<long>(times.size() / 2), times.end());
    result.push_back({bytes, times[times.size() / 2]});
  }
  echo.join();  // after at most 10 s when a message was lost
  if (transport == "ipc") std::filesystem::remove_all(dir);
  if (lost) throw RunError("a " + transport + " round trip between two sockets of this process got no answer within 10 s");
  return result;
}

Hockney fit_hockney(const std::vector<ExchangeSample>& s) {
  if (s.size() < 2) throw InputError("a Hockney fit needs two message sizes at least");
  std::vector<double> bytes, seconds;
  for (const ExchangeSample& e : s) bytes.push_back(static_cast<double>(e.bytes)), seconds.push_back(e.seconds);
  const LineFit f = line_fit(bytes, seconds);
  return {f.intercept, 1.0 / f.slope};
}

Hockney fit_loopback_tcp() { return fit_hockney(measure_exchange("tcp", {0, 1024, 65536}, 300)); }

}  // namespace mbsflow
