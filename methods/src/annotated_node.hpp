#pragma once
// A flow-graph node that tells ThreadSanitizer about the orderings oneTBB guarantees
// (tsan_annotations.hpp): it reads its captures after the thread that built the graph
// (call captures_published() once the graph is built), and it runs after the nodes that
// ran before it in the same solver (one token per solver object).
#include <oneapi/tbb/flow_graph.h>

#include <memory>
#include <vector>

#include "tsan_annotations.hpp"

namespace mbsflow {

using ContinueNode = tbb::flow::continue_node<tbb::flow::continue_msg>;

inline long graph_capture_token = 0;

inline void captures_published() { happens_before(&graph_capture_token); }

template <class Body>
ContinueNode& annotated_node(tbb::flow::graph& g, std::vector<std::unique_ptr<ContinueNode>>& nodes, long* token, Body body) {
  nodes.push_back(std::make_unique<ContinueNode>(g, [token, body](const tbb::flow::continue_msg&) {
    happens_after(&graph_capture_token);
    happens_after(token);
    body();
    happens_before(token);
    return tbb::flow::continue_msg();
  }));
  return *nodes.back();
}

}  // namespace mbsflow
