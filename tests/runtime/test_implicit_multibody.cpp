// The implicit methods evaluate their stages from several flow-graph nodes at once; on a
// multibody model (whole, or a loosely coupled submodel) those evaluations share one
// system's scratch, so they must not race: the same run gives the same numbers every time.
#include <catch2/catch.hpp>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

TEST_CASE("colloc and tirk on a multibody model give the same numbers every run", "[runtime][implicit]") {
  ChainParams chain;
  chain.bodies = 10;
  const Model m = make_chain(chain);
  for (Method method : {Method::colloc, Method::tirk}) {
    RunOptions o = options_from_model(m);
    o.method = method;
    o.t_end = o.t_start + 0.005;
    o.output_interval = 0.0005;
    std::vector<Eigen::VectorXd> first;
    for (int run = 0; run < 4; ++run) {
      MultibodySystem sys(m);
      test::MemorySink sink;
      run_simulation(sys, o, &sink);
      REQUIRE(sink.states.size() == 11);
      REQUIRE(sink.states.back() != sink.states.front());
      INFO(method_name(method) << ", run " << run);
      if (run == 0)
        first = sink.states;
      else
        CHECK(sink.states == first);
    }
  }
}

TEST_CASE("implicit submodels of a loosely coupled run give the same numbers every run", "[runtime][implicit][loose]") {
  ChainParams chain;
  chain.bodies = 12;
  const Model m = make_chain(chain);
  const Decomposition d = decompose(m, 2);
  RunOptions o = options_from_model(m);
  o.t_end = o.t_start + 0.005;
  o.method = Method::tirk;
  o.step = 0.0005;  // macro-step ends fall on this grid
  o.output_interval = 0.001;
  LooseOptions lo;
  lo.macro_step = 0.0005;
  lo.methods = {Method::tirk, Method::colloc};
  std::vector<Eigen::VectorXd> first;
  for (int run = 0; run < 4; ++run) {
    test::MemorySink sink;
    run_loose(m, d, o, lo, &sink);
    REQUIRE(sink.states.size() == 6);
    REQUIRE(sink.states.back() != sink.states.front());
    INFO("run " << run);
    if (run == 0)
      first = sink.states;
    else
      CHECK(sink.states == first);
  }
}

TEST_CASE("tirk on a stiff chain: sparse Jacobians by colour, KLU and SparseLU agree, and the dense output matches DOPRI5",
          "[runtime][implicit][sparse]") {
  ChainParams chain;
  chain.bodies = 40;  // 520 equations: the sparse path
  chain.stiffness = 1e8;  // translational modes near 2e4 rad/s
  const Model m = make_chain(chain);
  RunOptions o = options_from_model(m);
  o.t_end = o.t_start + 0.05;
  o.output_interval = 0.005;
  o.method = Method::dopri5;
  o.rtol = o.atol = 1e-10;
  MultibodySystem sys(m);
  test::MemorySink reference;
  run_simulation(sys, o, &reference);
  o.method = Method::tirk;
  o.rtol = o.atol = 1e-7;
  std::vector<test::MemorySink> runs(2);
  std::vector<RunSummary> summaries;
  for (const char* solver : {"klu", "sparselu"}) {
    o.linear_solver = solver;
    summaries.push_back(run_simulation(sys, o, &runs[summaries.size()]));
  }
  const RunSummary& s = summaries[0];
  INFO(s.steps << " steps, " << s.jacobians << " Jacobians, " << s.factorizations << " factorisations, " << s.evaluations
               << " evaluations");
  CHECK(s.jacobians > 0);
  CHECK(s.factorizations >= s.jacobians);
  // Differencing by colour: far fewer evaluations per Jacobian than the 520 columns.
  CHECK(s.evaluations < 100 * (s.jacobians + s.steps));
  REQUIRE(runs[0].states.size() == reference.states.size());
  double gap = 0.0, solvers = 0.0;
  for (std::size_t k = 0; k < reference.states.size(); ++k) {
    gap = std::max(gap, test::position_gap(sys, runs[0].states[k], reference.states[k]));
    solvers = std::max(solvers, (runs[0].states[k] - runs[1].states[k]).cwiseAbs().maxCoeff());
  }
  CHECK(gap < 1e-5);
  CHECK(solvers < 1e-6);  // roundoff apart, within the run's tolerance
  o.linear_solver = "lu";
  CHECK_THROWS_WITH(run_simulation(sys, o, nullptr), Catch::Contains("unknown linear solver 'lu'"));
}
