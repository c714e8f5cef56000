// Flexible bodies in partitioned runs: a part, its nodes and what is joined to them stay in
// one submodel (a joint at its frame may be cut), and a tightly coupled run is bit for bit
// the run of the whole model whatever the partition and thread count, checkpoints
// included; a loosely coupled one the same on any thread count, its overlap never
// borrowing the part (on worker processes: test_flexible_cluster.cpp).
#include <catch2/catch.hpp>
#include <cmath>

#include "flexible_rig.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "reference_run.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::hanging_rig;
using test::Rig;
using test::three_parts;


TEST_CASE("a flexible body, its nodes and the bodies joined to them are never cut apart, its frame's joints may be",
          "[runtime][flexible][partition]") {
  const Rig r = hanging_rig();
  const std::vector<int> piece = uncut_pieces(r.m);
  for (int i : {1, 2, 3, 4, r.a}) CHECK(piece[static_cast<std::size_t>(i)] == piece[0]);
  for (int i : {r.b, r.c, r.d}) CHECK(piece[static_cast<std::size_t>(i)] != piece[0]);
  CHECK(rigid_pieces(r.m)[static_cast<std::size_t>(r.b)] != rigid_pieces(r.m)[static_cast<std::size_t>(r.c)]);
  for (int k = 1; k <= 4; ++k)
    for (Partitioner p : {Partitioner::band, Partitioner::metis}) {
      const Decomposition d = decompose(r.m, k, p);
      for (int i : {1, 2, 3, 4, r.a}) CHECK(d.part_of_body[static_cast<std::size_t>(i)] == d.part_of_body[0]);
      const auto holder = static_cast<std::size_t>(d.part_of_body[0]);
      CHECK(d.submodels[holder].flexible == std::vector<int>{0});
      CHECK(d.layout().size() == MultibodySystem(r.m).dimension());
    }
  // The part weighs what its rates cost (some 3 us, dozens of rigid bodies with their joints).
  CHECK(body_costs(r.m)[0] > 40 * body_costs(r.m)[static_cast<std::size_t>(r.b)]);
  CHECK_THROWS_WITH(decompose(r.m, 5), Catch::Contains("rigid joints and flexible bodies") && Catch::Contains("4 pieces") &&
                                           Catch::Contains("6, 1, 1, 1"));
  std::vector<int> part = three_parts(r);
  part[static_cast<std::size_t>(r.a)] = 1;  // A is joined to node 24 by a rigid joint
  CHECK_THROWS_WITH(decompose(r.m, part, 3), Catch::Contains("rigid joint 'j1'"));
  Model compliant = r.m;
  compliant.joints[1].rigid = false;  // now compliant, and still at a node
  CHECK_THROWS_WITH(decompose(compliant, part, 3), Catch::Contains("body 'A' (part 1) is joined to flexible body 'bar' (part 0)"));
  CHECK_NOTHROW(decompose(r.m, three_parts(r), 3));
}

TEST_CASE("tight runs with a flexible body are bitwise identical across partitions and threads",
          "[runtime][flexible][identity]") {
  Rig r = hanging_rig();
  for (Method method : {Method::rk4, Method::dopri5}) {
    const test::MemorySink reference = test::reference_run(r.m, method);
    REQUIRE(reference.states.size() > 2);
    MultibodySystem sys(r.m);
    const Eigen::Index tail = sys.flexible_state(0);
    REQUIRE(reference.states.back().segment(tail, 4).norm() > 1e-6);  // the bar deforms
    REQUIRE(test::position_gap(sys, reference.states.back(), reference.states.front()) > 1e-3);
    std::vector<Decomposition> cuts{decompose(r.m, three_parts(r), 3)};
    for (int k : {2, 4}) cuts.push_back(decompose(r.m, k));
    for (const Decomposition& d : cuts)
      for (int threads : {1, 2})
        for (Executor ex : {Executor::flow_graph, Executor::barrier}) {
          INFO(method_name(method) << ", " << d.submodels.size() << " submodels, " << threads << " threads");
          test::MemorySink sink;
          run_partitioned(r.m, d, options_from_model(r.m), {threads, ex}, &sink);
          REQUIRE(sink.states.size() == reference.states.size());
          CHECK(test::same_snapshots(sink, reference));
        }
  }
}

TEST_CASE("a partitioned run with a flexible body resumes from its checkpoints bit for bit, in any partition",
          "[runtime][flexible][checkpoint]") {
  Rig r = hanging_rig();
  for (Method method : {Method::rk4, Method::dopri5}) {
    const test::MemorySink reference = test::reference_run(r.m, method);
    RunPlan plan;
    plan.options = options_from_model(r.m);
    plan.partition = decompose(r.m, three_parts(r), 3);
    std::vector<std::vector<std::uint8_t>> states;
    Checkpointing write;
    write.every_s = 1e-12;
    write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
    plan.options.checkpoint = &write;
    test::MemorySink full;
    const RunSummary whole = run(r.m, plan, &full);
    CHECK(test::same_snapshots(full, reference));
    REQUIRE(states.size() >= 4);
    for (int k : {0, 2}) {
      INFO(method_name(method) << ", resumed with " << k << " submodels");
      Checkpointing resume;
      resume.resume = states[states.size() / 2];
      resume.resume_from = "checkpoint";
      RunPlan again;
      again.options = options_from_model(r.m);
      if (k > 0) again.partition = decompose(r.m, k);
      again.options.checkpoint = &resume;
      test::MemorySink sink = full;
      const RunSummary resumed = run(r.m, again, &sink);
      CHECK(test::same_snapshots(sink, reference));
      CHECK(resumed.final_state == whole.final_state);
    }
  }
}

TEST_CASE("loose runs with a flexible body: the same bits on any thread count, no part borrowed, the coupling "
          "error of the extrapolation's order",
          "[runtime][flexible][loose]") {
  const Rig r = hanging_rig();
  const RunOptions o = options_from_model(r.m);
  MultibodySystem sys(r.m);
  const Eigen::VectorXd tight = run_simulation(sys, o, nullptr).final_state;
  const double h = *r.m.simulation.step;
  const Eigen::Index tail = sys.flexible_state(0);
  std::vector<int> part = three_parts(r);
  part[static_cast<std::size_t>(r.c)] = 3;  // B and C apart: they borrow each other
  const Decomposition d = decompose(r.m, part, 4);
  LooseOptions lo;
  lo.macro_step = 5 * h;
  lo.overlap = 1.0;  // a disturbance crosses every joint in far less: all that may be borrowed is
  const Decomposition wide = with_overlap(r.m, d, lo.overlap);
  CHECK(wide.submodels[0].borrowed == std::vector<int>{r.b, r.c, r.d});  // the part's owner borrows
  for (std::size_t p = 1; p < 4; ++p)  // the others never the bar, its nodes or A
    for (int b : wide.submodels[p].borrowed) CHECK((b == r.b || b == r.c || b == r.d));
  CHECK(wide.submodels[1].borrowed == std::vector<int>{r.c});
  test::MemorySink a, b;
  run_loose(r.m, d, o, lo, &a);
  lo.threads = 1;
  run_loose(r.m, d, o, lo, &b);
  REQUIRE(a.states.size() > 2);
  CHECK(a.states == b.states);
  // The bar's modes and the bodies' places against the tight run: the error of extrapolated
  // boundary values of order x falls as H^(x+1), without overlap (measured: modal errors 3.0e-5,
  // 7.2e-7, 1.7e-8 at H = 5 h of a deformation of 2.1e-4, ratios 1.91, 3.95, 9.07 to H = 10 h).
  // A submodel that followed its part's nodes with stale modes missed by 2.6e-4 whatever H.
  lo.overlap = 0.0;
  for (int x : {0, 1, 2}) {
    lo.extrapolation = x;
    double modes[2], places[2];
    for (int i : {0, 1}) {
      lo.macro_step = (i ? 10 : 5) * h;
      test::MemorySink c;
      run_loose(r.m, decompose(r.m, three_parts(r), 3), o, lo, &c);
      modes[i] = (c.states.back().segment(tail, 8) - tight.segment(tail, 8)).norm();
      places[i] = test::position_gap(sys, c.states.back(), tight);
    }
    INFO("extrapolation order " << x << ": modal error " << modes[0] << " at H = 5 h, " << modes[1] << " at 10 h; places "
                                << places[0] << ", " << places[1]);
    const double expected = std::pow(2.0, x + 1);
    CHECK(modes[0] < 0.2 * tight.segment(tail, 8).norm());
    CHECK(modes[1] / modes[0] > 0.75 * expected);
    CHECK(modes[1] / modes[0] < 1.33 * expected);
    CHECK(places[1] / places[0] > 0.75 * expected);
    CHECK(places[1] / places[0] < 1.33 * expected);
  }
}
