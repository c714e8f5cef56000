#include "schedules.hpp"

#include <oneapi/tbb/parallel_for.h>

namespace mbsflow {

namespace flow = tbb::flow;

FlowGraphSchedule::FlowGraphSchedule(const std::vector<Submodel>& subs, int chunk, int stages, StageWork work)
    : start_(graph_), work_(std::move(work)) {
  const std::size_t k = subs.size();
  const auto n_stages = static_cast<std::size_t>(stages);
  nodes_.reserve(static_cast<std::size_t>(chunk) * k * n_stages);
  for (int c = 0; c < chunk; ++c)
    for (std::size_t p = 0; p < k; ++p)
      for (int s = 0; s < stages; ++s)
        nodes_.push_back(std::make_unique<flow::continue_node<flow::continue_msg>>(graph_, [this, c, p, s](const flow::continue_msg&) {
          if (c < steps_) work_(p, s, c);
          return flow::continue_msg();
        }));
  auto node = [&](int c, std::size_t p, int s) -> flow::continue_node<flow::continue_msg>& {
    return *nodes_[(static_cast<std::size_t>(c) * k + p) * n_stages + static_cast<std::size_t>(s)];
  };
  // A finishing node runs the last of its successors that became ready itself and leaves
  // the others to be stolen. Registering each submodel's own next stage last keeps a
  // thread on its submodel (its data stays in that core's cache) while neighbours' next
  // stages go to their own threads.
  for (int c = 0; c < chunk; ++c) {
    for (std::size_t p = 0; p < k; ++p)
      for (const auto& e : subs[p].exchanges) {
        const auto q = static_cast<std::size_t>(e.neighbour);
        for (int s = 1; s < stages; ++s) flow::make_edge(node(c, q, s - 1), node(c, p, s));
        if (c > 0) flow::make_edge(node(c - 1, q, stages - 1), node(c, p, 0));
      }
    for (std::size_t p = 0; p < k; ++p) {
      for (int s = 1; s < stages; ++s) flow::make_edge(node(c, p, s - 1), node(c, p, s));
      if (c > 0) flow::make_edge(node(c - 1, p, stages - 1), node(c, p, 0));
      if (c == 0) flow::make_edge(start_, node(0, p, 0));
    }
  }
}

void FlowGraphSchedule::run(int steps) {
  steps_ = steps;
  start_.try_put(flow::continue_msg());
  graph_.wait_for_all();
}

void run_with_barriers(std::size_t parts, int steps, int stages, const StageWork& work) {
  for (int c = 0; c < steps; ++c)
    for (int s = 0; s < stages; ++s)
      tbb::parallel_for(std::size_t{0}, parts, [&](std::size_t p) { work(p, s, c); }, tbb::simple_partitioner());
}

}  // namespace mbsflow
