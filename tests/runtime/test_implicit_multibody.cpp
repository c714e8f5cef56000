// The implicit methods evaluate their stages from several flow-graph nodes at once; on a
// multibody model those evaluations share one MultibodySystem, so they must not race:
// the same run gives the same numbers every time.
#include <catch2/catch.hpp>

#include "mbsflow/graph/generators.hpp"
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
