// Overlapping submodels for loose coupling. A submodel that integrates its neighbours'
// bodies near the cut as well takes the extrapolated values only at the far edge of that
// overlap; what the extrapolation gets wrong there has to cross the overlap, at the speed
// at which the joints carry a disturbance, before it reaches an own body. An overlap wider
// than that distance for one macro step keeps the coupling error small even where the
// macro step is many times the stable step of the cut joints, where extrapolated values
// at the cut itself make the coupling unstable (see docs/parallel.md).
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/force_element.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "submodel_links.hpp"

namespace mbsflow {

Decomposition with_overlap(const Model& m, const Decomposition& d, double reach) {
  if (!(reach > 0.0) || d.submodels.size() < 2) return d;
  const std::vector<double> rate = joint_rates(m);
  // A force element of its own kind carries a disturbance as fast as the fastest joint could.
  const double element_time = 1.0 / std::max(1e-300, estimate_stable_step(m).lambda_max);
  const BodyLinks links(m);
  Decomposition out = d;
  const std::size_t n = m.bodies.size();
  // A flexible body's piece (uncut_pieces) is integrated by its owner alone: a neighbour
  // would have to hold the part whole, modes and all. The overlap stops at it.
  const std::vector<int> flexible_piece = flexible_piece_of(m);
  std::vector<double> time(n);
  using Entry = std::pair<double, int>;
  for (std::size_t p = 0; p < out.submodels.size(); ++p) {
    Submodel& s = out.submodels[p];
    // Dijkstra from the own bodies: the time a disturbance takes to get to each body.
    std::fill(time.begin(), time.end(), std::numeric_limits<double>::infinity());
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
    for (int b : s.own) {
      time[static_cast<std::size_t>(b)] = 0.0;
      queue.push({0.0, b});
    }
    auto relax = [&](int to, double t) {
      if (to == ground || t > reach || t >= time[static_cast<std::size_t>(to)]) return;
      if (flexible_piece[static_cast<std::size_t>(to)] >= 0 && d.part_of_body[static_cast<std::size_t>(to)] != static_cast<int>(p)) return;
      time[static_cast<std::size_t>(to)] = t;
      queue.push({t, to});
    };
    while (!queue.empty()) {
      const auto [t, b] = queue.top();
      queue.pop();
      if (t > time[static_cast<std::size_t>(b)]) continue;
      for (int j : links.joints[static_cast<std::size_t>(b)]) {
        const Joint& jt = m.joints[static_cast<std::size_t>(j)];
        const double r = rate[static_cast<std::size_t>(j)];
        if (r > 0.0) relax(jt.body1 == b ? jt.body2 : jt.body1, t + (std::isinf(r) ? 0.0 : 1.0 / r));
      }
      for (int e : links.elements[static_cast<std::size_t>(b)])
        for (int other : m.force_elements[static_cast<std::size_t>(e)]->bodies()) relax(other, t + element_time);
    }
    s.borrowed.clear();
    for (std::size_t b = 0; b < n; ++b)
      if (std::isfinite(time[b]) && d.part_of_body[b] != static_cast<int>(p)) s.borrowed.push_back(static_cast<int>(b));
  }
  link_submodels(m, out);
  return out;
}

}  // namespace mbsflow
