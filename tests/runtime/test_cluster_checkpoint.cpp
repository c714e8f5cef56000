// Checkpoints of tightly coupled runs on worker processes (workers on threads of the test,
// real ZeroMQ sockets): the coordinator's checkpoints hold the global state at a point
// every worker reached, and a run resumed from any of them, on workers or on threads,
// ends bit for bit as the uninterrupted run; a loosely coupled run's go on with the same
// workers.
#include <catch2/catch.hpp>
#include <optional>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/run.hpp"
#include "memory_sink.hpp"
#include "thread_workers.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

// A cluster run of m on two workers (three submodels), with `checkpoint` in its options,
// tightly or loosely coupled.
RunSummary on_workers(const Model& m, Checkpointing* checkpoint, MemorySink& sink, std::optional<LooseOptions> loose = {}) {
  ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
  ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
  for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
  c.workers[0].weight = 2;
  RunPlan plan;
  plan.options = options_from_model(m);
  plan.options.checkpoint = checkpoint;
  plan.partition = decompose(m, cluster_submodels(c));
  plan.cluster = c;
  plan.model_json = model_to_json(m);
  plan.loose = loose;
  return run(m, plan, &sink);
}

}  // namespace

TEST_CASE("a run on workers resumed from any of its checkpoints on workers or threads ends bit for bit as the uninterrupted one",
          "[runtime][cluster][checkpoint]") {
  ChainParams chain;
  chain.bodies = 120;
  for (Method method : {Method::rk4, Method::dopri5}) {
    INFO(method_name(method));
    Model m = short_run(make_chain(chain), 600);
    m.simulation.method = method;
    m.simulation.rtol = m.simulation.atol = 1e-7;
    m.simulation.output_every = 20;
    test::MemorySink reference;
    RunPlan whole;
    whole.options = options_from_model(m);
    const RunSummary ref = run(m, whole, &reference);
    REQUIRE(reference.states.size() > 10);

    std::vector<std::vector<std::uint8_t>> states;
    Checkpointing write;
    write.every_s = 1e-12;  // asked for again as soon as one is written
    write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
    test::MemorySink full;
    on_workers(m, &write, full);
    CHECK(same_snapshots(full, reference));  // taking checkpoints changes nothing
    REQUIRE(states.size() >= 2);
    for (std::size_t i : {std::size_t{0}, states.size() - 1}) {
      INFO("checkpoint " << i << " of " << states.size());
      Checkpointing resume;
      resume.resume = states[i];
      resume.resume_from = "checkpoint " + std::to_string(i);
      test::MemorySink again = full;  // the snapshots after the checkpoint are dropped and written again
      const RunSummary r = on_workers(m, &resume, again);
      CHECK(same_snapshots(again, reference));
      CHECK(r.final_state == ref.final_state);
      REQUIRE(r.resumed_at.has_value());
      // The same checkpoint goes on in this process, on threads, with another partition.
      RunPlan threads;
      threads.options = options_from_model(m);
      threads.options.checkpoint = &resume;
      threads.partition = decompose(m, 2);
      threads.parallel.threads = 2;
      test::MemorySink here = full;
      const RunSummary h = run(m, threads, &here);
      CHECK(same_snapshots(here, reference));
      CHECK(h.final_state == ref.final_state);
      CHECK(*h.resumed_at == *r.resumed_at);
    }
  }
}

TEST_CASE("a loosely coupled run on workers resumed from any of its checkpoints ends bit for bit as the uninterrupted one",
          "[runtime][cluster][checkpoint][loose]") {
  ChainParams chain;
  chain.bodies = 120;
  Model m = short_run(make_chain(chain), 400);
  m.simulation.output_every = 20;
  for (const double tol : {0.0, 1e-9}) {  // a fixed macro step; error control (all workers take the same ones)
    INFO("coupling tolerance " << tol);
    LooseOptions lo;
    lo.macro_step = 4 * *m.simulation.step;
    lo.coupling_tol = tol;
    lo.methods = {Method::rk4, Method::dopri5, Method::rk4};
    test::MemorySink reference;
    RunPlan threads;
    threads.options = options_from_model(m);
    threads.partition = decompose(m, 3);
    threads.loose = lo;
    run(m, threads, &reference);
    REQUIRE(reference.states.size() > 10);
    REQUIRE(!reference.coupling.empty());

    std::vector<std::vector<std::uint8_t>> states;
    Checkpointing write;
    write.every_s = 1e-12;
    write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
    test::MemorySink full;
    on_workers(m, &write, full, lo);
    CHECK(same_snapshots(full, reference));
    REQUIRE(states.size() >= 2);
    for (std::size_t i : {std::size_t{0}, states.size() / 2, states.size() - 1}) {
      INFO("checkpoint " << i << " of " << states.size());
      Checkpointing resume;
      resume.resume = states[i];
      resume.resume_from = "checkpoint " + std::to_string(i);
      test::MemorySink again = full;
      const RunSummary r = on_workers(m, &resume, again, lo);
      CHECK(same_snapshots(again, reference));
      CHECK(again.coupling.size() == reference.coupling.size());
      CHECK(same_records(again.coupling, reference.coupling));
      CHECK(r.resumed_at.has_value());
    }
  }
}
