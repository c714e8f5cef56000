// Simulation: a model stepped by the embedding program, and any registered method on a
// multibody model.
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

// A 2 kg body on a translational spring to ground along x, no gravity: x(t) = 0.1 cos(w t).
Model spring_mass(double k) {
  Model m;
  Body b = test::make_body("mass", 2.0, {1, 1, 1}, {0.1, 0.0, 0.0});
  m.bodies.push_back(b);
  m.joints.push_back(test::make_bushing(ground, 0, {0, 0, 0}, {0, 0, 0}, {k, k, k, 1, 1, 1}));
  m.simulation.t_end = 1.0;
  m.simulation.step = 1e-3;
  return m;
}

}  // namespace

TEST_CASE("Simulation stepped to the end gives run_simulation's numbers to the bit", "[runtime][stepping]") {
  const Model m = make_chain({.bodies = 20});
  for (Method method : {Method::rk4, Method::dopri5}) {
    INFO(method.name());
    RunOptions o = options_from_model(m);
    o.method = method;
    o.t_end = 0.2;
    MultibodySystem sys(m);
    const RunSummary whole = run_simulation(sys, o, nullptr);
    Simulation sim(m, o);
    long steps = 0;
    while (sim.step()) ++steps;
    CHECK(steps == whole.steps);
    CHECK(sim.time() == o.t_end);
    CHECK(sim.state() == whole.final_state);
    CHECK_FALSE(sim.step());  // nothing left
  }
}

TEST_CASE("advance_to lands on the asked time, with states and loads between steps", "[runtime][stepping]") {
  Model m = spring_mass(800.0);
  const double w = std::sqrt(800.0 / 2.0);
  Simulation sim(m);
  sim.advance_to(0.1234);
  CHECK(sim.time() == 0.1234);
  CHECK(sim.body(0).position.x() == Approx(0.1 * std::cos(w * 0.1234)).margin(1e-9));
  CHECK(sim.body(0).velocity.x() == Approx(-0.1 * w * std::sin(w * 0.1234)).margin(1e-7));
  CHECK_THROWS_AS(sim.advance_to(0.1), InputError);
  CHECK_THROWS_AS(sim.set_load(5, Eigen::Vector3d::Zero()), InputError);

  // A held load is the model's constant load, to rounding (it is added in another order).
  Model loaded = spring_mass(800.0);
  Load l;
  l.body = 0;
  l.force = {3.0, -1.0, 0.5};
  loaded.loads.push_back(l);
  Simulation a(loaded), b(m);
  b.set_load(0, Eigen::Vector3d(3.0, -1.0, 0.5));
  a.advance_to(0.5);
  b.advance_to(0.5);
  CHECK((a.state() - b.state()).cwiseAbs().maxCoeff() < 1e-12);
  // Taking it off again: the spring's free oscillation about x = 0 with its new amplitude
  // and phase; energy is conserved from then on (no damping).
  b.set_load(0, Eigen::Vector3d::Zero());
  const double e0 = b.system().energy(b.time(), b.state()).total();
  b.advance_to(1.0);
  CHECK(b.system().energy(b.time(), b.state()).total() == Approx(e0).epsilon(1e-7));
}

TEST_CASE("the implicit methods integrate a multibody model to its exact solution", "[runtime][stepping]") {
  const double k = 800.0, w = std::sqrt(k / 2.0);
  const Model m = spring_mass(k);
  for (Method method : {Method::colloc, Method::tirk}) {
    INFO(method.name());
    RunOptions o = options_from_model(m);
    o.method = method;
    o.rtol = o.atol = 1e-8;
    o.output_every = 10;  // snapshots every 10 ms of model time, from the dense output
    MultibodySystem sys(m);
    test::MemorySink sink;
    const RunSummary r = run_simulation(sys, o, &sink);
    REQUIRE(sink.times.size() == 101);
    double worst = 0.0;
    for (std::size_t i = 0; i < sink.times.size(); ++i) {
      CHECK(sink.times[i] == Approx(0.01 * static_cast<double>(i)).margin(1e-12));
      worst = std::max(worst, std::abs(sink.states[i][sys.layout().position(0)] - 0.1 * std::cos(w * sink.times[i])));
    }
    CHECK(worst < 1e-5);
    CHECK(r.steps > 10);
    CHECK(r.steps < 1000);  // its own steps, not the 1 ms grid
  }
}

namespace {

// A second spring to ground along x, as a user element: it has no analytic Jacobian.
struct ExtraSpring final : ForceElement {
  double k;
  explicit ExtraSpring(double k_) : k(k_) {}
  std::vector<int> bodies() const override { return {0}; }
  void evaluate(double, const Kinematics& kin, std::span<Wrench> out) const override {
    out[0].force = Eigen::Vector3d(-k * kin.position(0).x(), 0.0, 0.0);
  }
};

}  // namespace

TEST_CASE("an implicit Simulation given a force element without an analytic Jacobian goes on with differences",
          "[runtime][stepping][jacobian]") {
  const double k = 800.0, w = std::sqrt(2 * k / 2.0);  // the element doubles the stiffness along x
  RunOptions o = options_from_model(spring_mass(k));
  o.method = Method::tirk;
  o.rtol = o.atol = 1e-9;
  Simulation sim(spring_mass(k), o);
  sim.add_force_element(std::make_shared<ExtraSpring>(k));
  sim.advance_to(0.5);
  CHECK(sim.body(0).position.x() == Approx(0.1 * std::cos(w * 0.5)).margin(1e-6));
  CHECK(sim.stats().jacobians > 0);
}

TEST_CASE("an implicit Simulation with a held load is the model with that load", "[runtime][stepping][jacobian]") {
  // A held load is a constant wrench, which the analytic Jacobian covers: the method keeps
  // its stepper (and the state's storage, which the Python module's views point into).
  Model loaded = spring_mass(800.0);
  Load l;
  l.body = 0;
  l.force = {3.0, -1.0, 0.5};
  loaded.loads.push_back(l);
  for (Method method : {Method::tirk, Method::colloc}) {
    INFO(method.name());
    RunOptions o = options_from_model(loaded);
    o.method = method;
    o.rtol = o.atol = 1e-10;
    Simulation a(loaded, o), b(spring_mass(800.0), o);
    a.advance_to(0.1);
    b.advance_to(0.1);       // unloaded, with the analytic Jacobian
    b.set_state(a.state());  // then from the loaded model's state, with the load held
    const double* storage = b.state().data();
    b.set_load(0, Eigen::Vector3d(3.0, -1.0, 0.5));
    a.advance_to(0.5);
    b.advance_to(0.5);
    CHECK((a.state() - b.state()).cwiseAbs().maxCoeff() < 1e-7);
    CHECK(b.stats().jacobians > 0);
    CHECK(b.state().data() == storage);
    CHECK(b.system().has_analytic_jacobian());
  }
}
