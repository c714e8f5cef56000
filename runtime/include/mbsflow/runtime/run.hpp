#pragma once
// One entry point for every way to run a model. A RunPlan says how: the method, steps and
// output grid (RunOptions), the partition, tight or loose coupling, and where the
// submodels run (threads of this process, or worker processes). check_plan validates it
// once, before anything starts; run() hands it to the loop for it:
//
//   no partition              run_simulation   any method, the model whole
//   partition, tight          run_partitioned  RK4 / DOPRI5 stages spread over the submodels
//   partition, loose          run_loose        any method per submodel, macro steps
//   cluster (either coupling) run_cluster      the same loops in worker processes
#include <memory>
#include <optional>
#include <string>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

struct RunPlan {
  RunOptions options;
  std::optional<Decomposition> partition;  // none: the model whole, in one stepper
  std::optional<LooseOptions> loose;       // loose coupling at macro steps; none: tight
  ParallelOptions parallel;                // threads of this process
  // Worker processes instead of threads: the cluster, the model as model_to_json wrote it
  // (what the workers read), and a delay added to every boundary message (tests, benchmark).
  std::optional<ClusterConfig> cluster;
  std::string model_json;
  double exchange_delay_s = 0.0;
};

// What the loop that ran reports beyond RunSummary (the others stay empty).
struct RunStats {
  ParallelStats parallel;
  LooseStats loose;
  ClusterStats cluster;
};

// InputError for a plan no loop can run: bad options, loose coupling or a cluster without a
// partition, a method the coupling cannot use, loose settings that do not fit.
void check_plan(const Model& model, const RunPlan& plan);

// Checks the plan, then runs it; snapshots (global body order) go to the sink.
RunSummary run(const Model& model, const RunPlan& plan, ResultSink* sink, RunStats* stats = nullptr);
// The same with a model the caller holds shared: the run's systems share it, not copy it.
RunSummary run(std::shared_ptr<const Model> model, const RunPlan& plan, ResultSink* sink, RunStats* stats = nullptr);

}  // namespace mbsflow
