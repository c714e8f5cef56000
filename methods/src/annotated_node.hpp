#pragma once
// A flow-graph node that tells ThreadSanitizer about the orderings oneTBB guarantees
// (tsan_annotations.hpp): it reads its captures after the thread that built the graph
// (call captures_published() once the graph is built), and it runs after the nodes that
// ran before it in the same solver (one token per solver object).
#include <Eigen/Core>
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

// count nodes, node k running body(k), each after `from` (a node or a broadcast start)
// and before `to`: the fan-out and fan-in of work split by slice or by system. node: the
// solver's node maker (an annotated_node bound to its graph).
template <class NodeOf, class From, class Body>
void fan(NodeOf&& node, From& from, ContinueNode& to, Eigen::Index count, Body body) {
  for (Eigen::Index k = 0; k < count; ++k) {
    ContinueNode& n = node([body, k] { body(k); });
    tbb::flow::make_edge(from, n);
    tbb::flow::make_edge(n, to);
  }
}

}  // namespace mbsflow
