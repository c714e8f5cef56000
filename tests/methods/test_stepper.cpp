// The Stepper interface and its registry: every method behind it, on problems with exact
// solutions.
#include <catch2/catch.hpp>
#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "mbsflow/line_fit.hpp"
#include "mbsflow/methods/stepper.hpp"

#include "methods/oscillator_system.hpp"

using namespace mbsflow;

namespace {

using test::oscillator;  // y = cos t
Eigen::VectorXd exact(double t) { return Eigen::Vector2d(std::cos(t), -std::sin(t)); }

double end_error(Method m, const StepperSettings& o, double t_end = 2.0) {
  const StepperSystem sys = oscillator();
  auto stepper = make_stepper(m, sys, o);
  stepper->start(0.0, exact(0.0), t_end);
  while (!stepper->done()) stepper->step();
  REQUIRE(stepper->t() == t_end);
  return (stepper->y() - exact(t_end)).cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("stepper registry: every method by its name, unknown names listed", "[methods][stepper]") {
  for (const char* name : {"rk4", "dopri5", "colloc", "tirk"}) {
    INFO(name);
    REQUIRE(find_stepper(name) != nullptr);
    CHECK(find_method(name)->name() == std::string(name));
  }
  CHECK_FALSE(find_method("euler"));
  CHECK(method_list() == "rk4, dopri5, colloc, tirk");
  const StepperSystem sys = oscillator();
  CHECK_THROWS_WITH(make_stepper(Method("euler"), sys, {}), "unknown method 'euler' (rk4, dopri5, colloc, tirk)");
  CHECK_THROWS_AS(make_stepper(Method::rk4, sys, {}), InputError);  // no step
  StepperSettings bad;
  bad.variant = "radau4";
  CHECK_THROWS_AS(make_stepper(Method::tirk, sys, bad), InputError);
  bad.variant = "two";
  CHECK_THROWS_AS(make_stepper(Method::colloc, sys, bad), InputError);
}

TEST_CASE("stepper registry: each method's capabilities, and the methods named by one", "[methods][stepper]") {
  CHECK(method_names([](const StepperEntry& e) { return e.implicit; }, "and") == "colloc and tirk");
  CHECK(method_names([](const StepperEntry& e) { return e.tight_stages > 0; }, "or") == "rk4 or dopri5");
  CHECK(method_names([](const StepperEntry& e) { return !e.adaptive; }, "or") == "rk4");
  CHECK(method_names([](const StepperEntry&) { return false; }, "or").empty());
  CHECK(stepper_entry(Method::rk4).tight_stages == 4);
  CHECK(stepper_entry(Method::dopri5).tight_stages == 7);
  CHECK_THROWS_WITH(stepper_entry(Method("euler")), "unknown method 'euler' (rk4, dopri5, colloc, tirk)");
  // An implicit method controls its error: fixed_step is its option, not a kind of method.
  for (const StepperEntry& e : stepper_entries()) {
    INFO(e.method.name());
    if (e.implicit) CHECK(e.adaptive);
    // A tight stage scheme is explicit: its stages are taken one after another.
    if (e.tight_stages > 0) CHECK_FALSE(e.implicit);
  }
}

TEST_CASE("rk4 stepper: order 4, fixed steps landing on t_end", "[methods][stepper]") {
  std::vector<double> h, err;
  for (double step : {0.1, 0.05, 0.025}) {
    StepperSettings o;
    o.step = step;
    h.push_back(step);
    err.push_back(end_error(Method::rk4, o, 2.03));  // not a whole number of steps
  }
  CHECK(log_log_slope(h, err) == Approx(4.0).margin(0.3));
}

TEST_CASE("adaptive steppers meet their tolerance and converge as it shrinks", "[methods][stepper]") {
  for (Method m : {Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    StepperSettings o;
    o.threads = 1;
    o.rtol = o.atol = 1e-5;
    const double loose = end_error(m, o);
    o.rtol = o.atol = 1e-9;
    const double tight = end_error(m, o);
    CHECK(loose < 1e-3);
    CHECK(tight < 1e-7);
    CHECK(tight < loose / 100);
  }
}

TEST_CASE("dense output inside each step follows the solution", "[methods][stepper]") {
  for (Method m : {Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    const StepperSystem sys = oscillator();
    StepperSettings o;
    o.threads = 1;
    o.rtol = o.atol = 1e-8;
    auto stepper = make_stepper(m, sys, o);
    stepper->start(0.0, exact(0.0), 3.0);
    double worst = 0.0;
    Eigen::VectorXd out;
    long steps = 0;
    while (!stepper->done()) {
      stepper->step();
      ++steps;
      for (double theta : {0.0, 0.3, 0.5, 0.9, 1.0}) {
        const double t = stepper->t_previous() + theta * (stepper->t() - stepper->t_previous());
        stepper->dense(t, out);
        worst = std::max(worst, (out - exact(t)).cwiseAbs().maxCoeff());
      }
    }
    CHECK(steps > 3);
    CHECK(worst < 1e-5);
  }
}

TEST_CASE("a restarted stepper goes on from the new state and keeps its step size", "[methods][stepper]") {
  for (Method m : {Method::rk4, Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    const StepperSystem sys = oscillator();
    StepperSettings o;
    o.threads = 1;
    o.step = 0.01;
    o.rtol = o.atol = 1e-8;
    auto stepper = make_stepper(m, sys, o);
    stepper->start(0.0, exact(0.0), 1.0);
    while (!stepper->done()) stepper->step();
    const double h = stepper->next_step();
    // On to t = 2 from the state it reached (as loose coupling's macro steps do).
    stepper->start(1.0, stepper->y(), 2.0);
    if (m == Method::rk4)
      CHECK(h == 0.0);
    else
      CHECK(stepper->next_step() == h);
    while (!stepper->done()) stepper->step();
    CHECK((stepper->y() - exact(2.0)).cwiseAbs().maxCoeff() < 1e-6);
    // set_state: the same system from another state, here the exact one at t = 2.
    stepper->start(2.0, exact(2.0), 2.5);
    while (!stepper->done()) stepper->step();
    CHECK((stepper->y() - exact(2.5)).cwiseAbs().maxCoeff() < 1e-6);
    CHECK(stepper->stats().accepted > 0);
    CHECK(stepper->stats().evaluations >= stepper->stats().accepted);
  }
}

TEST_CASE("after_step projects every accepted step of every method", "[methods][stepper]") {
  // y' = (-y1, y0) keeps |y| = 1; a projection onto the unit circle must be applied after
  // every step, so that |y| = 1 to rounding after each.
  for (Method m : {Method::rk4, Method::dopri5, Method::colloc, Method::tirk}) {
    INFO(m.name());
    StepperSystem sys;
    sys.size = 2;
    sys.rhs = [](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
      d.resize(2);
      d << -y[1], y[0];
    };
    long projections = 0;
    sys.after_step = [&](double, Eigen::VectorXd& y) {
      y.normalize();
      ++projections;
    };
    StepperSettings o;
    o.threads = 1;
    o.step = 0.05;
    o.rtol = o.atol = 1e-4;
    auto stepper = make_stepper(m, sys, o);
    stepper->start(0.0, Eigen::Vector2d(1.0, 0.0), 5.0);
    while (!stepper->done()) {
      stepper->step();
      CHECK(std::abs(stepper->y().norm() - 1.0) < 1e-14);
    }
    CHECK(projections == stepper->stats().accepted);
  }
}

TEST_CASE("implicit steppers end a run whose steps fall a rounding short of its end", "[methods][stepper]") {
  // Ten fixed steps of 0.1 add up to 0.9999999999999999: within the integrators' 1e-12 of
  // t = 1, so they stop there, and a stepper that waited for t >= 1 called them for ever
  // (an adaptive run can end the same way: test_checkpoint's stiff chain did). The tenth
  // step is the last: done() right after it, so a run writes no checkpoint after it.
  for (Method m : {Method::colloc, Method::tirk}) {
    INFO(m.name());
    StepperSettings o;
    o.threads = 1;
    o.step = 0.1;
    o.fixed_step = true;
    const StepperSystem sys = oscillator();
    auto stepper = make_stepper(m, sys, o);
    stepper->start(0.0, exact(0.0), 1.0);
    int calls = 0;
    while (!stepper->done() && calls < 100) {
      stepper->step();
      ++calls;
    }
    CHECK(stepper->done());
    CHECK(calls == 10);
    CHECK(stepper->t() == 1.0);
    CHECK((stepper->y() - exact(1.0)).cwiseAbs().maxCoeff() < 1e-3);
  }
}

TEST_CASE("implicit steppers evaluate on the copies another_rhs makes with the same numbers", "[methods][stepper]") {
  for (Method m : {Method::colloc, Method::tirk}) {
    INFO(method_name(m));
    StepperSettings o;
    o.rtol = o.atol = 1e-8;
    o.threads = 4;
    auto run = [&](const StepperSystem& sys) {
      auto stepper = make_stepper(m, sys, o);
      stepper->start(0.0, exact(0.0), 2.0);
      while (!stepper->done()) stepper->step();
      return stepper->y();
    };
    const Eigen::VectorXd alone = run(oscillator());
    // Each copy flags a call that overlaps another of its own (the pool hands a copy to
    // one call at a time); the system's own rhs is not called.
    std::atomic<int> copies = 0, overlaps = 0, own_calls = 0;
    StepperSystem pooled = oscillator();
    const StepperSystem::Rhs f = pooled.rhs;
    pooled.rhs = [&, f](double t, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
      ++own_calls;
      f(t, y, d);
    };
    pooled.another_rhs = [&, f]() -> StepperSystem::Rhs {
      ++copies;
      auto busy = std::make_shared<std::atomic<bool>>(false);
      return [&, f, busy](double t, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
        if (busy->exchange(true)) ++overlaps;
        f(t, y, d);
        busy->store(false);
      };
    };
    CHECK(run(pooled) == alone);
    CHECK(copies >= 1);
    CHECK(copies <= 16);  // a few, made when every one was busy; not one per call
    CHECK(overlaps == 0);
    CHECK(own_calls == 0);
  }
}
