#pragma once
// What one boundary message costs on this host (for mbsflow bench cluster; not installed).
#include <cstddef>
#include <string>
#include <vector>

namespace mbsflow {

// The cost of the boundary exchange on this host: one-way time of messages of each size
// between two threads over tcp on 127.0.0.1 or ipc, with the sockets the exchange uses
// (PUSH to PULL), from `round_trips` round trips each (the median).
struct ExchangeSample {
  std::size_t bytes = 0;
  double seconds = 0.0;
};
std::vector<ExchangeSample> measure_exchange(const std::string& transport, const std::vector<std::size_t>& sizes,
                                             int round_trips);

// Hockney's model t(m) = alpha + m / beta, fitted by least squares.
struct Hockney {
  double alpha = 0.0;  // s
  double beta = 0.0;   // bytes/s
  double time(double bytes) const { return alpha + bytes / beta; }
};
Hockney fit_hockney(const std::vector<ExchangeSample>& samples);
// The fit mbsflow plan and bench parallel predict with: tcp between two processes on this
// host (loopback), messages of 0, 1 KiB and 64 KiB, 300 round trips each.
Hockney fit_loopback_tcp();

// Gigabit Ethernet as predictions assume it (not measured: this host has no network to
// measure): the payload rate of 1 Gbit/s less Ethernet/IP/TCP framing, and the NIC, switch
// and wire latency added to the software cost of a message measured on loopback.
constexpr double gbe_bytes_per_s = 117.0e6;
constexpr double gbe_extra_latency_s = 25.0e-6;
inline Hockney gigabit_ethernet(const Hockney& loopback) {
  return {loopback.alpha + gbe_extra_latency_s, loopback.beta < gbe_bytes_per_s ? loopback.beta : gbe_bytes_per_s};
}

}  // namespace mbsflow
