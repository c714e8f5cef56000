#pragma once
// Runs a decomposed model on threads: every submodel integrates its own bodies and pulls
// its ghost bodies' values from their owners at every stage. Each own body's numbers are
// bit for bit those of the single-partition run (run_simulation), whatever the partition
// and thread count: the local models sum forces in global order, the stage arithmetic is
// the methods' own (rk4::, dopri5::), element by element, and DOPRI5's error norm adds
// the elements' terms in global order (the one global reduction per step attempt).
#include <memory>
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

enum class Executor {
  flow_graph,  // oneTBB flow graph: a submodel's stage starts when its neighbours' values are in
  barrier,     // the seed's scheme: all submodels compute a stage, barrier, all exchange
};

struct ParallelOptions {
  int threads = 0;  // 0: all cores
  Executor executor = Executor::flow_graph;
};

struct ParallelStats {
  int threads = 0;
  double busy_seconds = 0.0;   // summed over threads: time in submodel stage work
  double wait_fraction = 0.0;  // 1 - busy / (wall x threads): waiting for neighbours or the barrier
};

// RK4 or DOPRI5. Snapshots in global body order go to the sink.
RunSummary run_partitioned(const Model& model, const Decomposition& d, const RunOptions& options,
                           const ParallelOptions& parallel, ResultSink* sink, ParallelStats* stats = nullptr);
// The same with a model the caller holds shared: the whole system (for the sink) shares it
// instead of copying it (a million bodies' model is a gigabyte).
RunSummary run_partitioned(std::shared_ptr<const Model> model, const Decomposition& d, const RunOptions& options,
                           const ParallelOptions& parallel, ResultSink* sink, ParallelStats* stats = nullptr);

// Partitions for a thread count: one submodel per thread, fewer for small models (and
// never more than the pieces uncut_pieces leaves).
int default_partitions(const Model& model, int threads);

}  // namespace mbsflow
