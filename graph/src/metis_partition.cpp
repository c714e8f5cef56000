// k-way partition by METIS (libmetis-dev): a multilevel graph partitioner that balances
// the body costs and minimises the cut joints; far better than band cuts on bushy trees
// and plates, where a band order cuts along a long diagonal.
#include <metis.h>

#include <map>
#include <optional>
#include <vector>

#include "metis_partition.hpp"

namespace mbsflow {

std::optional<std::vector<int>> metis_partition(const Model& m, const std::vector<double>& cost, int k) {
  const auto n = static_cast<idx_t>(m.bodies.size());
  if (k < 2 || n < k) return std::nullopt;
  // Adjacency with the number of joints between two bodies as edge weight.
  std::vector<std::map<idx_t, idx_t>> adj(static_cast<std::size_t>(n));
  for (const Joint& j : m.joints) {
    if (j.body1 == ground) continue;
    ++adj[static_cast<std::size_t>(j.body1)][j.body2];
    ++adj[static_cast<std::size_t>(j.body2)][j.body1];
  }
  std::vector<idx_t> xadj{0}, adjncy, adjwgt, vwgt;
  for (idx_t b = 0; b < n; ++b) {
    for (const auto& [other, w] : adj[static_cast<std::size_t>(b)]) {
      adjncy.push_back(other);
      adjwgt.push_back(w);
    }
    xadj.push_back(static_cast<idx_t>(adjncy.size()));
    vwgt.push_back(static_cast<idx_t>(cost[static_cast<std::size_t>(b)] + 0.5));
  }
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // the same partition every time
  options[METIS_OPTION_NUMBERING] = 0;
  idx_t nvtxs = n, ncon = 1, nparts = k, objval = 0;
  real_t ubvec = 1.03;  // 3 % imbalance allowed
  std::vector<idx_t> part(static_cast<std::size_t>(n));
  const int status = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.empty() ? nullptr : adjncy.data(), vwgt.data(),
                                         nullptr, adjwgt.empty() ? nullptr : adjwgt.data(), &nparts, nullptr, &ubvec,
                                         options, &objval, part.data());
  if (status != METIS_OK) return std::nullopt;
  std::vector<int> out(part.begin(), part.end());
  std::vector<bool> used(static_cast<std::size_t>(k), false);
  for (int p : out) used[static_cast<std::size_t>(p)] = true;
  for (bool u : used)
    if (!u) return std::nullopt;  // METIS may leave a part empty on tiny graphs
  return out;
}

}  // namespace mbsflow
