// Which worker of a cluster runs which submodel.
#include <numeric>

#include "mbsflow/error.hpp"
#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow {
namespace {

bool explicit_lists(const ClusterConfig& c) {
  return !c.workers.empty() && !c.workers.front().submodels.empty();
}

}  // namespace

int cluster_submodels(const ClusterConfig& c) {
  int k = 0;
  for (const ClusterWorker& w : c.workers) k += explicit_lists(c) ? static_cast<int>(w.submodels.size()) : w.weight;
  return k;
}

std::vector<int> assign_submodels(const ClusterConfig& c, int k) {
  if (c.workers.empty()) throw InputError("the cluster has no workers");
  if (k < static_cast<int>(c.workers.size()))
    throw InputError(std::to_string(k) + " submodels for " + std::to_string(c.workers.size()) +
                     " workers: every worker needs at least one");
  std::vector<int> worker_of(static_cast<std::size_t>(k), -1);
  if (explicit_lists(c)) {
    for (std::size_t w = 0; w < c.workers.size(); ++w) {
      if (c.workers[w].submodels.empty())
        throw InputError("worker " + c.workers[w].name + " lists no submodels, the others do: list them for all or none");
      for (int s : c.workers[w].submodels) {
        if (s < 0 || s >= k)
          throw InputError("worker " + c.workers[w].name + " lists submodel " + std::to_string(s) + ", but there are " +
                           std::to_string(k) + " (0.." + std::to_string(k - 1) + ")");
        if (worker_of[static_cast<std::size_t>(s)] >= 0)
          throw InputError("submodel " + std::to_string(s) + " is listed by two workers");
        worker_of[static_cast<std::size_t>(s)] = static_cast<int>(w);
      }
    }
    for (int s = 0; s < k; ++s)
      if (worker_of[static_cast<std::size_t>(s)] < 0)
        throw InputError("submodel " + std::to_string(s) + " is listed by no worker");
    return worker_of;
  }
  // Contiguous runs in submodel order (neighbours in the band order stay together), sized
  // in proportion to the weights, at least one each (largest remainders get the rest).
  const double total = std::accumulate(c.workers.begin(), c.workers.end(), 0.0,
                                       [](double a, const ClusterWorker& w) { return a + w.weight; });
  const std::size_t n = c.workers.size();
  std::vector<int> count(n, 1);
  for (int left = k - static_cast<int>(n); left > 0; --left) {
    auto behind = [&](std::size_t w) { return c.workers[w].weight / total * k - count[w]; };
    std::size_t most = 0;
    for (std::size_t w = 1; w < n; ++w)
      if (behind(w) > behind(most)) most = w;
    ++count[most];
  }
  int s = 0;
  for (std::size_t w = 0; w < n; ++w)
    for (int i = 0; i < count[w]; ++i) worker_of[static_cast<std::size_t>(s++)] = static_cast<int>(w);
  return worker_of;
}

}  // namespace mbsflow
