// The implicit methods evaluate their stages from several flow-graph nodes at once; on a
// multibody model (whole, or a loosely coupled submodel) those evaluations share one
// system's scratch, so they must not race: the same run gives the same numbers every time.
#include <catch2/catch.hpp>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

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
