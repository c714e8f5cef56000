#include "run_prediction.hpp"

#include <algorithm>

#include "wire_format.hpp"
#include "mbsflow/error.hpp"
#include "partitioned_state.hpp"

namespace mbsflow {

double boundary_message_bytes(std::size_t bodies) {
  return static_cast<double>(bodies * partitioned::body_numbers * sizeof(double) + sizeof(wire::ExchangeHeader));
}

StagePrediction predict_stage(const Decomposition& d, int hosts, int threads, double seconds_per_cost, const Hockney& network) {
  const int k = static_cast<int>(d.submodels.size());
  if (hosts < 1 || threads < 1 || k != hosts * threads)
    throw InputError("predict_stage: " + std::to_string(k) + " submodels for " + std::to_string(hosts) + " hosts of " +
                     std::to_string(threads) + " threads");
  const auto host_of = [threads](int submodel) { return submodel / threads; };
  StagePrediction p;
  p.hosts = hosts;
  p.threads = threads;
  p.cut_joints = d.cut_joints;
  p.imbalance = d.imbalance;
  double slowest = -1.0;
  for (int h = 0; h < hosts; ++h) {
    double compute = 0.0, exchange = 0.0;
    for (int s = h * threads; s < (h + 1) * threads; ++s) {
      const Submodel& sub = d.submodels[static_cast<std::size_t>(s)];
      compute = std::max(compute, seconds_per_cost * sub.estimated_time());
      // What arrives from other hosts: one message per neighbour submodel there.
      for (const Submodel::Exchange& e : sub.exchanges) {
        if (host_of(e.neighbour) == h) continue;
        const double bytes = boundary_message_bytes(e.to.size());
        exchange += network.time(bytes);
        ++p.messages;
        p.bytes += bytes;
      }
    }
    if (compute + exchange > slowest) {
      slowest = compute + exchange;
      p.compute_s = compute;
      p.exchange_s = exchange;
    }
  }
  return p;
}

}  // namespace mbsflow
