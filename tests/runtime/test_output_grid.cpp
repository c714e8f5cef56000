// The output grid is given in seconds of model time and does not follow the integrator's
// steps: the same snapshot times whatever the method, step or run mode.
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

Model chain(int bodies, double t_end) {
  ChainParams c;
  c.bodies = bodies;
  Model m = make_chain(c);
  m.simulation.t_end = t_end;
  return m;
}

// Every snapshot but the last lies on k * dt; the last one at t_end.
void check_grid(const std::vector<double>& times, double t_end, double dt) {
  const auto expected = static_cast<std::size_t>(std::floor(t_end / dt * (1 + 1e-12))) + 1;
  const bool end_on_grid = std::abs(std::round(t_end / dt) * dt - t_end) < 1e-12;
  REQUIRE(times.size() == expected + (end_on_grid ? 0 : 1));
  for (std::size_t i = 0; i + 1 < times.size(); ++i) CHECK(times[i] == Approx(static_cast<double>(i) * dt).margin(1e-13));
  CHECK(times.back() == t_end);
}

}  // namespace

TEST_CASE("output interval: the same snapshot times for RK4, DOPRI5 and the implicit methods", "[runtime][output]") {
  Model m = chain(6, 0.02);
  m.simulation.output_interval = 0.0025;
  for (const char* name : {"rk4", "dopri5", "tirk", "colloc"}) {
    m.simulation.method = *find_method(name);
    const RunOptions o = options_from_model(m);
    INFO(name << ": step " << o.step);
    if (m.simulation.method == Method::rk4) {
      // no step given: the stable step, shortened to fit the interval a whole number of times
      const double estimate = estimate_stable_step(m).step;
      CHECK(o.step <= estimate);
      CHECK(o.step > 0.5 * estimate);
      CHECK(std::abs(std::round(0.0025 / o.step) * o.step - 0.0025) < 1e-15);
    }
    MultibodySystem sys(m);
    MemorySink sink;
    run_simulation(sys, o, &sink);
    check_grid(sink.times, 0.02, 0.0025);
  }
}

TEST_CASE("output interval: RK4 on a grid of whole steps equals output_every", "[runtime][output]") {
  Model m = chain(5, 0.03);
  m.simulation.step = 1e-4;
  m.simulation.output_every = 25;
  MultibodySystem sys(m);
  MemorySink every, interval;
  run_simulation(sys, options_from_model(m), &every);
  m.simulation.output_interval = 25 * 1e-4;
  run_simulation(sys, options_from_model(m), &interval);
  REQUIRE(every.times.size() == interval.times.size());
  for (std::size_t i = 0; i < every.times.size(); ++i) {
    CHECK(every.times[i] == interval.times[i]);
    CHECK(every.states[i] == interval.states[i]);
  }
}

TEST_CASE("output interval: a given RK4 step that does not divide it is refused", "[runtime][output]") {
  Model m = chain(3, 0.01);
  m.simulation.step = 3e-4;
  m.simulation.output_interval = 1e-3;
  MultibodySystem sys(m);
  CHECK_THROWS_AS(run_simulation(sys, options_from_model(m), nullptr), InputError);
  CHECK_THROWS_WITH(run_simulation(sys, options_from_model(m), nullptr),
                    Catch::Contains("not a whole number of rk4 steps"));
}

TEST_CASE("output interval: DOPRI5 without a step writes a fixed number of snapshots, not one per stable step",
          "[runtime][output]") {
  Model m = chain(4, 2.0);
  m.simulation.method = Method::dopri5;
  m.simulation.output_every = 1;
  const RunOptions o = options_from_model(m);
  CHECK(o.output_interval == Approx(2.0 / 1000));
  REQUIRE(2.0 / o.step > 2000);  // the stable step is far finer than the grid
  MultibodySystem sys(m);
  MemorySink sink;
  run_simulation(sys, o, &sink);
  check_grid(sink.times, 2.0, 2.0 / 1000);
  m.simulation.output_every = 10;
  CHECK(options_from_model(m).output_interval == Approx(2.0 / 100));
}

TEST_CASE("output interval: partitioned and loosely coupled runs write on the same grid", "[runtime][output]") {
  Model m = chain(12, 0.01);
  m.simulation.step = 2e-5;
  m.simulation.output_interval = 1e-3;
  const Decomposition d = decompose(m, 3);
  for (Method method : {Method::rk4, Method::dopri5}) {
    m.simulation.method = method;
    INFO(method.name());
    MemorySink sink;
    run_partitioned(m, d, options_from_model(m), {2, Executor::flow_graph}, &sink);
    check_grid(sink.times, 0.01, 1e-3);
  }
  m.simulation.method = Method::rk4;
  LooseOptions lo;
  lo.macro_step = 1e-4;
  lo.threads = 2;
  MemorySink loose;
  run_loose(m, d, options_from_model(m), lo, &loose);
  check_grid(loose.times, 0.01, 1e-3);
}
