#include "mbsflow/runtime/run.hpp"

#include "mbsflow/error.hpp"
#include "sink_runner.hpp"
#include "tight_coupling.hpp"

namespace mbsflow {

void check_plan(const Model& model, const RunPlan& plan) {
  const RunOptions& o = plan.options;
  check_options(o);
  stepper_entry(o.method);  // a method that exists
  if (plan.exchange_delay_s != 0.0 && !plan.cluster)
    throw InputError("{exchange_delay}: only for runs on worker processes");
  if (plan.loose) {
    if (!plan.partition) throw InputError("loose coupling needs a partition of the model into submodels");
    check_loose_options(*plan.loose, plan.partition->submodels.size());
  }
  if (plan.cluster) {
    if (!plan.partition) throw InputError("a run on worker processes needs a partition of the model into submodels");
    if (plan.model_json.empty()) throw InputError("a run on worker processes needs the model's JSON for the workers");
    check_cluster_run(model, o, {plan.loose ? &*plan.loose : nullptr, plan.exchange_delay_s});
  } else if (plan.partition && !plan.loose) {
    tight_stages(o.method);  // a method whose stages the submodels exchange
  }
}

namespace {

// The kind of run a checkpoint's state is of: "simulation" (one stepper) or "tight".
std::string checkpoint_kind(const Checkpointing& c) {
  StateReader in(c.resume, c.resume_from);
  return in.text();
}

// The run of either entry point: `shared` holds `model` when the caller shares it, else
// null, and then the model is copied once, for the systems to share.
RunSummary run_plan(const Model& model, std::shared_ptr<const Model> shared, const RunPlan& plan, ResultSink* sink,
                    RunStats* stats) {
  check_plan(model, plan);
  RunStats local;
  RunStats& st = stats ? *stats : local;
  const LooseOptions* loose = plan.loose ? &*plan.loose : nullptr;
  if (!shared) shared = std::make_shared<const Model>(model);
  if (plan.cluster)
    return run_cluster(shared, plan.model_json, *plan.partition, *plan.cluster, plan.options, sink, &st.cluster,
                       {loose, plan.exchange_delay_s});
  // Loose coupling of one submodel is a plain run (no macro steps to restart the method at).
  const bool one = plan.partition && plan.partition->submodels.size() == 1;
  if (loose && !one) return run_loose(shared, *plan.partition, plan.options, *loose, sink, &st.loose);
  // A tight run's numbers do not depend on the partition, so a checkpoint goes on in
  // whichever loop wrote it, whatever partition (or none) the resumed run was given.
  const Checkpointing* c = plan.options.checkpoint;
  const std::string kind = c && !c->resume.empty() ? checkpoint_kind(*c) : "";
  if (kind == "tight" && !plan.partition) return run_partitioned(shared, decompose(model, 1), plan.options, plan.parallel, sink, &st.parallel);
  if (plan.partition && !loose && kind != "simulation")
    return run_partitioned(shared, *plan.partition, plan.options, plan.parallel, sink, &st.parallel);
  MultibodySystem system(shared, static_cast<int>(model.bodies.size()));
  phase_done(plan.options, "build the system");
  RunOptions whole = plan.options;
  if (whole.threads == 0) whole.threads = plan.parallel.threads;
  return run_simulation(system, whole, sink);
}

}  // namespace

RunSummary run(const Model& model, const RunPlan& plan, ResultSink* sink, RunStats* stats) {
  return run_plan(model, nullptr, plan, sink, stats);
}

RunSummary run(std::shared_ptr<const Model> shared, const RunPlan& plan, ResultSink* sink, RunStats* stats) {
  const Model& model = *shared;
  return run_plan(model, std::move(shared), plan, sink, stats);
}

}  // namespace mbsflow
