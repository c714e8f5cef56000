// Rigid joints inside submodels: the partitioners keep rigid clusters whole, an explicit
// partition that cuts one is refused, and tight runs stay bit for bit the same whatever
// the partition and thread count; loose ones the same on any thread count.
#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "pendulum_row.hpp"
#include "reference_run.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::pendulum_row;

TEST_CASE("partitions never cut a rigid joint, and say why when they cannot be made", "[runtime][rigid]") {
  const Model m = pendulum_row();
  const std::vector<int> piece = rigid_pieces(m);
  for (int k = 1; k <= 6; ++k)
    for (Partitioner p : {Partitioner::band, Partitioner::metis}) {
      const Decomposition d = decompose(m, k, p);
      for (const Joint& j : m.joints)
        if (is_kinematic(j.type) && j.rigid && j.body1 != ground)
          CHECK(d.part_of_body[static_cast<std::size_t>(j.body1)] == d.part_of_body[static_cast<std::size_t>(j.body2)]);
    }
  CHECK_THROWS_WITH(decompose(m, 7), Catch::Contains("rigid joints leave only 6 pieces") && Catch::Contains("3, 3, 3"));
  std::vector<int> part(m.bodies.size(), 0);
  part[1] = 1;
  CHECK_THROWS_WITH(decompose(m, part, 2), Catch::Contains("rigid joint 'j1'") && Catch::Contains("a cut may only pass through"));
}

TEST_CASE("tight runs with rigid clusters are bitwise identical across partitions and threads", "[runtime][rigid][identity]") {
  Model m = pendulum_row();
  for (Method method : {Method::rk4, Method::dopri5}) {
    const test::MemorySink reference = test::reference_run(m, method);
    REQUIRE(reference.states.size() > 2);
    REQUIRE(reference.states.back() != reference.states.front());
    CHECK(MultibodySystem(m).constraint_violation(reference.times.back(), reference.states.back()) < 1e-10);
    for (int k : {2, 3, 6})
      for (int threads : {1, 2})
        for (Executor ex : {Executor::flow_graph, Executor::barrier}) {
          test::MemorySink sink;
          run_partitioned(m, decompose(m, k), options_from_model(m), {threads, ex}, &sink);
          INFO(method_name(method) << ", " << k << " partitions, " << threads << " threads");
          REQUIRE(sink.states.size() == reference.states.size());
          CHECK(test::same_snapshots(sink, reference));
        }
  }
}

TEST_CASE("loose runs with rigid clusters inside submodels: the same bits on any thread count, close to the tight run",
          "[runtime][rigid][loose]") {
  Model m = pendulum_row();
  const RunOptions o = options_from_model(m);
  MultibodySystem sys(m);
  const Eigen::VectorXd tight = run_simulation(sys, o, nullptr).final_state;
  const Decomposition d = decompose(m, 3);
  LooseOptions lo;
  lo.macro_step = 2 * *m.simulation.step;
  lo.extrapolation = 1;
  test::MemorySink a, b;
  run_loose(m, d, o, lo, &a);
  lo.threads = 1;
  run_loose(m, d, o, lo, &b);
  REQUIRE(a.states.size() > 2);
  CHECK(a.states == b.states);
  // The rigid joints hold inside each submodel; only the cut (bushings, compliant joints) lags.
  CHECK(sys.constraint_violation(a.times.back(), a.states.back()) < 1e-10);
  const double gap = test::position_gap(sys, a.states.back(), tight);
  CHECK(gap > 0.0);
  CHECK(gap < 1e-3);
}
