#include "schedules.hpp"

#include "tsan_annotations.hpp"

namespace mbsflow {

namespace flow = tbb::flow;

namespace {
// Orders a node's reading of its own captures after the thread that built and started the
// graph (for ThreadSanitizer; see tsan_annotations.hpp). Taken first, before any capture.
long start_token = 0;
}  // namespace

FlowGraphSchedule::FlowGraphSchedule(const std::vector<Submodel>& subs, int chunk, int stages, StageWork work,
                                     bool barriers)
    : start_(graph_), work_(std::move(work)) {
  const std::size_t k = subs.size();
  const auto n_stages = static_cast<std::size_t>(stages);
  nodes_.reserve(static_cast<std::size_t>(chunk) * k * n_stages);
  for (int c = 0; c < chunk; ++c)
    for (std::size_t p = 0; p < k; ++p)
      for (int s = 0; s < stages; ++s)
        nodes_.push_back(std::make_unique<flow::continue_node<flow::continue_msg>>(graph_, [this, c, p, s](const flow::continue_msg&) {
          happens_after(&start_token);
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
  auto inputs = [&](std::size_t p) {  // the other submodels whose values p needs
    std::vector<std::size_t> q;
    if (barriers) {
      for (std::size_t o = 0; o < k; ++o)
        if (o != p) q.push_back(o);
    } else {
      for (const auto& e : subs[p].exchanges) q.push_back(static_cast<std::size_t>(e.neighbour));
    }
    return q;
  };
  for (int c = 0; c < chunk; ++c) {
    for (std::size_t p = 0; p < k; ++p)
      for (std::size_t q : inputs(p)) {
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
  happens_before(&start_token);
  start_.try_put(flow::continue_msg());
  graph_.wait_for_all();
}

}  // namespace mbsflow
