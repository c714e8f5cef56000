// The snapshots of a loose run do not depend on its macro steps: they come on the output
// grid from the submodels' dense output, whatever the macro step.
#include <catch2/catch.hpp>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

TEST_CASE("loose coupling: macro steps longer than the output interval, snapshots on the output grid",
          "[runtime][loose][output]") {
  ChainParams c;
  c.bodies = 60;
  Model m = make_chain(c);
  m.simulation.t_end = 0.1;
  m.simulation.output_every = 3;
  RunOptions o = options_from_model(m);
  MultibodySystem sys(m);
  test::MemorySink tight;
  run_simulation(sys, o, &tight);
  const Decomposition d = decompose(m, 3);
  LooseOptions lo;
  lo.macro_step = 16 * o.step;  // not a multiple of the output interval
  for (Method method : {Method::rk4, Method::dopri5}) {
    INFO(method_name(method));
    RunOptions mine = o;
    mine.method = method;
    mine.rtol = mine.atol = 1e-11;
    test::MemorySink sink;
    LooseStats st;
    const RunSummary r = run_loose(m, d, mine, lo, &sink, &st);
    REQUIRE(sink.times.size() == tight.times.size());
    CHECK(sink.times == tight.times);
    CHECK(sink.states.back() == r.final_state);
    // The macro steps are the ones asked for (the last one ends at t_end).
    for (std::size_t i = 0; i + 1 < st.records.size(); ++i)
      CHECK(st.records[i].t_end - st.records[i].t_start == Approx(lo.macro_step).epsilon(1e-9));
    double gap = 0.0;
    for (std::size_t i = 0; i < sink.states.size(); ++i) gap = std::max(gap, test::position_gap(sys, sink.states[i], tight.states[i]));
    // RK4: the snapshots lie on its steps, the tight run's; DOPRI5: from its dense output.
    CHECK(gap < (method == Method::rk4 ? 1e-9 : 1e-6));
    // Quaternions of unit length, as in any snapshot.
    const StateLayout& l = sys.layout();
    for (const Eigen::VectorXd& y : sink.states)
      for (Eigen::Index b = 0; b < l.bodies; ++b) CHECK(std::abs(y.segment<4>(l.orientation(b)).norm() - 1.0) < 1e-14);
  }
}
