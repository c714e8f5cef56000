// run(model, plan, sink): every plan gives what the loop it stands for gives, to the bit,
// and a plan no loop can run is refused before anything starts.
#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/run.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;

namespace {

Model small_chain() {
  ChainParams chain;
  chain.bodies = 24;
  Model m = make_chain(chain);
  m.simulation.step = 0.5 * estimate_stable_step(m).step;
  m.simulation.t_end = m.simulation.t_start + 40 * *m.simulation.step;
  m.simulation.output_every = 8;
  return m;
}

}  // namespace

TEST_CASE("run(model, plan, sink) gives what the loop of the plan gives, bit for bit", "[runtime][plan]") {
  const Model m = small_chain();
  const Decomposition d = decompose(m, 3);
  for (Method method : {Method::rk4, Method::dopri5}) {
    RunPlan plan;
    plan.options = options_from_model(m);
    plan.options.method = method;
    INFO(method_name(method));

    test::MemorySink whole, whole_direct;
    MultibodySystem sys(m);
    run_simulation(sys, plan.options, &whole_direct);
    const RunSummary r = run(m, plan, &whole);
    CHECK(whole.states == whole_direct.states);
    CHECK(r.final_state == whole_direct.states.back());

    plan.partition = d;
    plan.parallel = {2, Executor::flow_graph};
    test::MemorySink tight, tight_direct;
    RunStats stats;
    run(m, plan, &tight, &stats);
    run_partitioned(m, d, plan.options, plan.parallel, &tight_direct);
    CHECK(tight.states == tight_direct.states);
    CHECK(tight.states == whole.states);  // a tight run equals the whole one
    CHECK(stats.parallel.threads == 2);

    LooseOptions lo;
    lo.macro_step = 4 * plan.options.step;
    plan.loose = lo;
    test::MemorySink loose, loose_direct;
    run(m, plan, &loose, &stats);
    run_loose(m, d, plan.options, lo, &loose_direct);
    CHECK(loose.states == loose_direct.states);
    CHECK(loose.states != whole.states);  // loose coupling is another method
    CHECK(!stats.loose.records.empty());
  }
}

TEST_CASE("run(model, plan, sink) refuses a plan no loop can run, before it starts", "[runtime][plan]") {
  const Model m = small_chain();
  auto refused = [&](const RunPlan& plan, const std::string& part) {
    test::MemorySink sink;
    try {
      run(m, plan, &sink);
      FAIL("the plan ran");
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(part) != std::string::npos);
    }
    CHECK(sink.states.empty());
  };
  RunPlan plan;
  plan.options = options_from_model(m);
  plan.options.t_end = plan.options.t_start;
  refused(plan, "t_end must be greater than t_start");
  plan.options = options_from_model(m);

  RunPlan loose = plan;
  loose.loose = LooseOptions{};
  loose.loose->macro_step = 4 * plan.options.step;
  refused(loose, "loose coupling needs a partition");
  loose.partition = decompose(m, 2);
  loose.loose->macro_step = -1.0;
  refused(loose, "macro");

  RunPlan cluster = plan;
  cluster.cluster = ClusterConfig{};
  refused(cluster, "needs a partition");

  RunPlan delayed = plan;
  delayed.exchange_delay_s = 0.01;
  refused(delayed, "exchange_delay: only for runs on worker processes");

  RunPlan implicit = plan;
  implicit.options.method = Method::colloc;
  implicit.partition = decompose(m, 2);
  refused(implicit, "exchanges RK4 or DOPRI5 stages; colloc");
}
