// The rule the design holds above all: a tightly coupled run gives bit for bit the same
// snapshots whatever the partition count, thread count and executor.
#include <catch2/catch.hpp>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;

namespace {

Model with_short_run(Model m) {
  m.simulation.step = 0.5 * estimate_stable_step(m).step;  // well inside, so the model moves smoothly
  m.simulation.t_end = m.simulation.t_start + 40 * *m.simulation.step;
  m.simulation.output_every = 5;
  return m;
}

std::vector<Model> models() {
  TrainParams train;
  train.wagons = 3;  // 21 bodies
  GridParams grid;
  grid.rows = 6;
  grid.cols = 7;
  ChainParams chain;
  chain.bodies = 40;
  RandomTreeParams tree;
  tree.bodies = 50;
  tree.cycles = 12;
  return {with_short_run(make_chain(chain)), with_short_run(make_grid(grid)), with_short_run(make_train(train)),
          with_short_run(make_random_tree(tree))};
}

}  // namespace

TEST_CASE("partitioned runs equal the single-partition run bit for bit", "[runtime][identity]") {
  for (const Model& m : models()) {
    MultibodySystem sys(m);
    test::MemorySink reference;
    run_simulation(sys, options_from_model(m), &reference);
    REQUIRE(reference.states.size() == 9);
    // The model really moved, so equality means something.
    REQUIRE(reference.states.back() != reference.states.front());
    for (int k : {1, 2, 3, 7, 16}) {
      const Decomposition d = decompose(m, k);
      for (int threads : {1, 2, 4})
        for (Executor ex : {Executor::flow_graph, Executor::barrier}) {
          test::MemorySink sink;
          run_partitioned(m, d, options_from_model(m), {threads, ex}, &sink);
          INFO(m.name << ", " << k << " partitions, " << threads << " threads, "
                      << (ex == Executor::flow_graph ? "flow graph" : "barrier"));
          REQUIRE(sink.states.size() == reference.states.size());
          bool identical = sink.times == reference.times;
          for (std::size_t i = 0; i < sink.states.size(); ++i) identical = identical && sink.states[i] == reference.states[i];
          CHECK(identical);
        }
    }
  }
}
