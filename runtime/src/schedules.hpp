#pragma once
// How the stages of the submodels are scheduled on threads. work(p, s, c) is submodel p's
// stage s of step c of a chunk of steps.
#include <oneapi/tbb/flow_graph.h>

#include <functional>
#include <memory>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"

namespace mbsflow {

using StageWork = std::function<void(std::size_t p, int s, int c)>;

// A oneTBB flow graph built once and run for every chunk: node (c, p, s) waits for stage
// s-1 of submodel p and of the neighbours it takes ghosts from (for s = 0: the last stage
// of the previous step), so a submodel's stage starts as soon as its neighbours' values
// are in; no barrier but the end of the chunk. With barriers, every node waits for the
// previous stage of all submodels instead: the seed's scheme, a barrier per stage.
class FlowGraphSchedule {
 public:
  FlowGraphSchedule(const std::vector<Submodel>& subs, int chunk, int stages, StageWork work, bool barriers = false);
  void run(int steps);  // steps <= chunk; later steps' nodes do nothing

 private:
  tbb::flow::graph graph_;
  tbb::flow::broadcast_node<tbb::flow::continue_msg> start_;
  std::vector<std::unique_ptr<tbb::flow::continue_node<tbb::flow::continue_msg>>> nodes_;
  StageWork work_;
  int steps_ = 0;
};

}  // namespace mbsflow
