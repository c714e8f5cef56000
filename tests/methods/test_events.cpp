// Events on every stepper's dense output: zeros of cos t found at (2k+1) pi/2 to the
// accuracy of the solution, directions filtered, and a terminal event (a falling ball
// reaching the ground at sqrt(2 h / g)) ends the run at the event.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <vector>

#include "mbsflow/methods/events.hpp"

#include "methods/oscillator_system.hpp"

using namespace mbsflow;

namespace {

using test::oscillator;  // y = cos t

StepperSettings settings_for(Method m, double rtol) {
  StepperSettings o;
  o.rtol = o.atol = rtol;
  if (m == Method::rk4) o.step = 1e-3;
  return o;
}

std::vector<Event> oscillator_events(Method m, int direction, double rtol) {
  const StepperSystem sys = oscillator();
  auto stepper = make_stepper(m, sys, settings_for(m, rtol));
  stepper->start(0.0, Eigen::Vector2d(1, 0), 10.0);
  EventDetector events({{"y = 0", [](double, const Eigen::VectorXd& y) { return y(0); }, direction, false}});
  const std::vector<Event> found = integrate_with_events(*stepper, events);
  CHECK(stepper->t() == 10.0);  // not terminal: the run goes on to the end
  return found;
}

}  // namespace

TEST_CASE("events: zeros of cos t on every method's dense output, with directions", "[methods][events]") {
  const double pi = std::numbers::pi;
  for (Method m : {Method::rk4, Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    const std::vector<Event> all = oscillator_events(m, 0, 1e-9);
    REQUIRE(all.size() == 3);  // pi/2, 3pi/2, 5pi/2 in [0, 10]
    for (std::size_t k = 0; k < all.size(); ++k) {
      INFO("event " << k << " at " << all[k].t);
      // Located to the accuracy of the solution (rtol 1e-9; rk4 at h = 1e-3: error 1e-12).
      CHECK(std::abs(all[k].t - (2 * double(k) + 1) * pi / 2) < 1e-7);
      CHECK(all[k].direction == (k % 2 == 0 ? -1 : 1));
      CHECK(std::abs(all[k].y(0)) < 1e-7);  // the state there is on the zero too
    }
    const std::vector<Event> rising = oscillator_events(m, 1, 1e-9);
    REQUIRE(rising.size() == 1);
    CHECK(std::abs(rising[0].t - 3 * pi / 2) < 1e-7);
    const std::vector<Event> falling = oscillator_events(m, -1, 1e-9);
    CHECK(falling.size() == 2);
  }
}

TEST_CASE("events: the location follows the tolerance", "[methods][events]") {
  // Looser tolerances locate the zero less precisely, but within the solution's own error.
  for (Method m : {Method::dopri5, Method::colloc, Method::tirk}) {
    for (double rtol : {1e-4, 1e-6, 1e-8}) {
      const std::vector<Event> all = oscillator_events(m, 0, rtol);
      REQUIRE(all.size() == 3);
      const double error = std::abs(all[2].t - 5 * std::numbers::pi / 2);
      INFO(m.name() << " at rtol " << rtol << ": event time error " << error);
      CHECK(error < 100 * rtol);
    }
  }
}

TEST_CASE("events: a terminal event ends the run at the event", "[methods][events]") {
  // A ball dropped from 10 m: h = 10 - g t^2 / 2 reaches 0 at sqrt(20 / g).
  StepperSystem ball;
  ball.size = 2;
  ball.rhs = [](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
    d.resize(2);
    d << y[1], -9.81;
  };
  for (Method m : {Method::rk4, Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    auto stepper = make_stepper(m, ball, settings_for(m, 1e-8));
    stepper->start(0.0, Eigen::Vector2d(10, 0), 5.0);
    EventDetector events({{"ground", [](double, const Eigen::VectorXd& y) { return y(0); }, -1, true},
                          {"never", [](double, const Eigen::VectorXd& y) { return y(0) - 20; }, 0, false}});
    const std::vector<Event> found = integrate_with_events(*stepper, events);
    REQUIRE(found.size() == 1);
    CHECK(found[0].index == 0);
    CHECK(std::abs(found[0].t - std::sqrt(20 / 9.81)) < 1e-9);  // a quadratic: every method's dense output is exact
    CHECK(stepper->t() == found[0].t);                          // the stepper stands at the event
    CHECK(std::abs(stepper->y()(0)) < 1e-9);
    CHECK(std::abs(stepper->y()(1) + std::sqrt(20 * 9.81)) < 1e-7);
    CHECK_FALSE(stepper->done());  // it may go on from there
  }
}

TEST_CASE("events: clear errors", "[methods][events]") {
  CHECK_THROWS_AS(EventDetector({{"none", {}, 0, false}}), InputError);
  CHECK_THROWS_AS(EventDetector({{"bad", [](double, const Eigen::VectorXd&) { return 0.0; }, 2, false}}), InputError);
  const StepperSystem sys = oscillator();
  auto stepper = make_stepper(Method::dopri5, sys, {});
  stepper->start(0.0, Eigen::Vector2d(1, 0), 1.0);
  stepper->step();
  EventDetector events({{"y", [](double, const Eigen::VectorXd& y) { return y(0); }, 0, false}});
  CHECK_THROWS_WITH(events.after_step(*stepper), Catch::Contains("reset()"));
}
