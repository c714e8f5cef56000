#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {
Model oscillator() {
  Model m;
  m.bodies.push_back(make_body("b", 2.0, {0.5, 0.5, 0.5}, {1.0, 0, 0}));
  m.joints.push_back(make_bushing(ground, 0, {}, {}, {800, 800, 800, 0, 0, 0}, {8, 8, 8, 0, 0, 0}));
  return m;
}
double exact_x(double t) {
  const double w = 20.0, zeta = 8.0 / (2 * std::sqrt(800 * 2.0)), wd = w * std::sqrt(1 - zeta * zeta);
  return std::exp(-zeta * w * t) * (std::cos(wd * t) + zeta * w / wd * std::sin(wd * t));
}
}  // namespace

TEST_CASE("RK4 run: snapshots every k steps, the last one exactly at t_end", "[runtime]") {
  MultibodySystem sys(oscillator());
  RunOptions o;
  o.t_end = 1.05;
  o.step = 0.01;
  o.output_every = 10;
  MemorySink sink;
  const RunSummary r = run_simulation(sys, o, &sink);
  CHECK(r.steps == 105);
  REQUIRE(sink.times.size() == 12);  // t = 0, 0.1 .. 1.0, 1.05
  CHECK(sink.times[1] == Approx(0.1));
  CHECK(sink.times.back() == 1.05);
  CHECK(sink.ended);
  CHECK(sink.states.back()[0] == Approx(exact_x(1.05)).margin(1e-4));  // RK4 at omega h = 0.2
}

TEST_CASE("DOPRI5 run: uniform output grid from dense output, within tolerance", "[runtime]") {
  MultibodySystem sys(oscillator());
  RunOptions o;
  o.method = Method::dopri5;
  o.t_end = 2.0;
  o.step = 0.01;
  o.output_every = 5;
  o.rtol = o.atol = 1e-9;
  MemorySink sink;
  const RunSummary r = run_simulation(sys, o, &sink);
  REQUIRE(sink.times.size() == 41);
  double max_err = 0.0;
  for (std::size_t i = 0; i < sink.times.size(); ++i) {
    CHECK(sink.times[i] == Approx(0.05 * static_cast<double>(i)).margin(1e-12));
    max_err = std::max(max_err, std::abs(sink.states[i][0] - exact_x(sink.times[i])));
  }
  CHECK(max_err < 1e-7);
  // Output comes from the dense output: a finer output grid does not change the steps.
  MultibodySystem again(oscillator());
  o.output_every = 1;
  MemorySink fine;
  const RunSummary r1 = run_simulation(again, o, &fine);
  CHECK(fine.times.size() == 201);
  CHECK(r1.steps == r.steps);
  CHECK(fine.states.back() == sink.states.back());
}

TEST_CASE("a diverging run stops with a message naming time, body and a working step", "[runtime]") {
  ChainParams p;
  p.bodies = 5;
  const Model m = make_chain(p);
  MultibodySystem sys(m);
  RunOptions o;
  o.t_end = 1.0;
  o.step = 4.0 * estimate_stable_step(m).step;
  MemorySink sink;
  try {
    run_simulation(sys, o, &sink);
    FAIL("no divergence");
  } catch (const RunError& e) {
    const std::string msg = e.what();
    INFO(msg);
    CHECK(msg.find("run diverged at t = ") == 0);
    CHECK(msg.find("body 'link") != std::string::npos);
    CHECK(msg.find("exceeds the estimated stability limit") != std::string::npos);
    CHECK(msg.find("try step = ") != std::string::npos);  // the library names settings, the CLI shows flags
  }
  CHECK(sink.ended);  // the sink was closed, keeping what was written
  CHECK(sink.times.size() >= 1);
}

TEST_CASE("the train runs over its rough track with wheelsets on the track", "[runtime]") {
  TrainParams p;
  p.wagons = 2;
  const Model m = make_train(p);
  MultibodySystem sys(m);
  RunOptions o = options_from_model(m);
  o.t_end = 1.0;
  MemorySink sink;
  run_simulation(sys, o, &sink);
  const Eigen::VectorXd& y = sink.states.back();
  const StateLayout& s = sys.layout();
  // On the track: every wheelset, in every snapshot, is exactly where its driver puts it
  // (initial position + v t + the track's vertical and lateral profile), level.
  REQUIRE(!m.drivers.empty());
  REQUIRE(sink.states.size() >= 5);
  for (std::size_t k = 0; k < sink.states.size(); ++k) {
    const double t = sink.times[k];
    for (const Driver& d : m.drivers) {
      const Body& b = m.bodies[static_cast<std::size_t>(d.body)];
      for (int a = 0; a < 3; ++a) {
        const auto ax = static_cast<std::size_t>(a);
        const double expected = b.position[ax] + d.velocity[ax] * t + evaluate(d.displacement[ax], t).value;
        CHECK(sink.states[k][s.position(d.body) + a] == Approx(expected).margin(1e-12));
      }
      CHECK(sink.states[k].segment<4>(s.orientation(d.body)) == Eigen::Vector4d(1, 0, 0, 0));
    }
  }
  // The track is rough (the profile moves the wheelsets), and they moved 30 m forward;
  // the car bodies follow at the same speed and stay up.
  const Driver& d0 = m.drivers.front();
  double largest = 0.0;
  for (std::size_t k = 0; k < sink.states.size(); ++k)
    largest = std::max(largest, std::abs(sink.states[k][s.position(d0.body) + 1] - m.bodies[static_cast<std::size_t>(d0.body)].position[1]));
  CHECK(largest > 1e-4);
  CHECK(y[s.position(2)] == Approx(m.bodies[2].position[0] + 30.0).epsilon(1e-12));
  CHECK(y[s.velocity(0)] == Approx(30.0).margin(0.05));
  CHECK(std::abs(y[s.position(0) + 1] - 2.0) < 0.01);
}
