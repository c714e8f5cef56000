// The library checks a Model that an embedding program built by hand: a bad field is an
// mbsflow::InputError naming it, never a crash or a run of NaN.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"

using namespace mbsflow;

TEST_CASE("a hand-built model with a bad field is an InputError naming it", "[graph][limits]") {
  ChainParams chain;
  chain.bodies = 3;
  const Model good = make_chain(chain);
  REQUIRE_NOTHROW(check_model(good));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::function<void(Model&)>, std::string>> cases = {
      {[](Model& m) { m.bodies[1].mass = -1.0; }, "body 1 'link1' mass: must be a finite number > 0 (got -1)"},
      {[](Model& m) { m.bodies[1].mass = 0.0; }, "mass: must be a finite number > 0"},
      {[nan](Model& m) { m.bodies[2].position[1] = nan; }, "body 2 'link2' position: must be finite (got nan)"},
      {[](Model& m) { m.bodies[0].inertia = {1.0, 1.0, -1.0, 0.0, 0.0, 0.0}; }, "inertia: must be positive definite"},
      {[](Model& m) { m.bodies[0].orientation = {0.0, 0.0, 0.0, 0.0}; }, "orientation: must be a rotation quaternion"},
      {[](Model& m) { m.joints[0].body2 = 7; }, "body2: no body 7"},
      {[](Model& m) { m.joints[0].body1 = -5; }, "body1: no body -5"},
      {[](Model& m) { m.joints[1].body1 = m.joints[1].body2; }, "to itself"},
      {[nan](Model& m) { m.joints[0].stiffness.set(2, nan); }, "stiffness: must be finite"},
      {[](Model& m) { m.joints[0].damping.set(0, -1.0); }, "damping: must be >= 0"},
      {[](Model& m) { m.loads.push_back(Load{}); m.loads.back().body = 3; }, "load 0 body: no body 3"},
      {[](Model& m) { m.drivers.push_back(Driver{}); m.drivers.back().body = -1; }, "driver 0 body: no body -1"},
      {[](Model& m) { m.simulation.t_end = m.simulation.t_start; }, "t_end must be > t_start"},
      {[nan](Model& m) { m.simulation.step = nan; }, "simulation step: must be a finite number > 0"},
      {[](Model& m) { m.simulation.output_every = 0; }, "output_every: must be >= 1"},
      {[nan](Model& m) { m.gravity[2] = nan; }, "gravity: must be finite"},
      {[](Model& m) { m.force_elements.push_back(nullptr); }, "force element 0: is null"},
  };
  for (const auto& [spoil, message] : cases) {
    Model m = good;
    spoil(m);
    INFO(message);
    bool thrown = false;
    try {
      MultibodySystem sys(m);  // every run compiles one
    } catch (const InputError& e) {
      thrown = true;
      CHECK_THAT(std::string(e.what()), Catch::Contains(message));
    }
    CHECK(thrown);
  }
}
