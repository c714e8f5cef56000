#pragma once
// How the stages of the submodels are scheduled on threads. work(p, s, c) is submodel p's
// stage s of step c of a chunk of steps.
#include <oneapi/tbb/flow_graph.h>

#include <functional>
#include <memory>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"

namespace mbsflow {

// The part of a stage a node computes: all of it, or (with remote inputs) the inner half
// that needs no ghost values and then the edge half that does.
enum class Half { whole, inner, edge };
using StageWork = std::function<void(std::size_t p, int s, int c, Half half)>;

// Submodels that run in other processes. Each local stage is then two nodes, its inner
// half (no ghost values needed: it runs while they travel) and its edge half, which comes
// after a proxy node per remote neighbour whose body, wait(c, q, p, s), returns once
// remote q's values of stage input s of chunk step c for local p are in. The proxies are
// chained between the two halves, so at most one node per local submodel waits at a
// time: with at least as many threads as local submodels, a waiting proxy never keeps a
// runnable stage from a thread.
struct RemoteInputs {
  std::vector<char> local;  // per submodel: 1 if its stages run here
  std::function<void(int c, std::size_t q, std::size_t p, int s)> wait;
};

// A oneTBB flow graph built once and run for every chunk: node (c, p, s) waits for stage
// s-1 of submodel p and of the neighbours it takes ghosts from (for s = 0: the last stage
// of the previous step), so a submodel's stage starts as soon as its neighbours' values
// are in; no barrier but the end of the chunk. With barriers, every node waits for the
// previous stage of all submodels instead: the seed's scheme, a barrier per stage. With
// remote inputs, only local submodels get nodes, and a remote neighbour is a proxy node.
// With a lag L (loose coupling, one stage a step), step c waits for the neighbours' step
// c - 1 - L only, so a submodel may run up to L steps ahead of them.
class FlowGraphSchedule {
 public:
  FlowGraphSchedule(const std::vector<Submodel>& subs, int chunk, int stages, StageWork work, bool barriers = false,
                    const RemoteInputs* remote = nullptr, int lag = 0);
  void run(int steps);  // steps <= chunk; later steps' nodes do nothing

 private:
  using Node = tbb::flow::continue_node<tbb::flow::continue_msg>;
  tbb::flow::graph graph_;
  tbb::flow::broadcast_node<tbb::flow::continue_msg> start_;
  std::vector<std::unique_ptr<Node>> nodes_;  // null for remote submodels
  std::vector<std::unique_ptr<Node>> proxies_;
  StageWork work_;
  int steps_ = 0;
  long finish_token_ = 0;  // for ThreadSanitizer: every node ran before run() returns
};

// A FlowGraphSchedule whose stages tell ThreadSanitizer what they wait for: a stage of
// submodel p reads what p and its neighbours wrote before and what the calling thread set
// up (see tsan_annotations.hpp).
class Scheduler {
 public:
  Scheduler(const Decomposition& d, int chunk, int stages, StageWork work, bool barriers = false,
            const RemoteInputs* remote = nullptr, int lag = 0);
  void run(int steps);

 private:
  const std::vector<Submodel>& subs_;
  std::vector<long> tokens_;  // one synchronisation token per submodel
  long caller_ = 0;
  StageWork work_;
  std::unique_ptr<FlowGraphSchedule> graph_;
};

}  // namespace mbsflow
