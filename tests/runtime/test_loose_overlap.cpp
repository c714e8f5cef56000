// Loose coupling at macro steps many times the stable step of the cut joints: without an
// overlap the coupling blows up; with one it stays stable and close to the tight run, the
// error falling as the overlap grows. Error control, rollback and energy at such steps.
#include <catch2/catch.hpp>
#include <cmath>
#include <regex>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

// A chain of 160 links in 2 submodels, RK4 at its stable step for `steps` steps, and a
// macro step of a whole number of steps at least `times` the cut joint's RK4 stable step.
struct LongMacroSteps {
  Model m;
  RunOptions o;
  Decomposition d;
  double cut_step, H;
  MultibodySystem sys;
  Eigen::VectorXd tight;
  LongMacroSteps(double damping_ratio, int steps, double times) : m(chain(damping_ratio)), sys(m) {
    m.simulation.t_end = m.simulation.t_start + steps * estimate_stable_step(m).step;
    m.simulation.output_every = steps;
    o = options_from_model(m);
    d = decompose(m, 2);
    cut_step = cut_joint_stable_step(m, d);
    H = std::ceil(times * cut_step / o.step) * o.step;
    tight = run_simulation(sys, o, nullptr).final_state;
  }
  static Model chain(double damping_ratio) {
    ChainParams c;
    c.bodies = 160;
    c.damping_ratio = damping_ratio;
    return make_chain(c);
  }
  LooseOptions options(int order, double overlap = -1.0) const {
    LooseOptions lo;
    lo.macro_step = H;
    lo.extrapolation = order;
    lo.overlap = overlap;
    return lo;
  }
  double gap(const Eigen::VectorXd& y) const { return test::position_gap(sys, y, tight); }
};

}  // namespace

TEST_CASE("overlap: at macro steps 10x the cut joint's stable step the coupling is stable and close to the tight run",
          "[runtime][loose][overlap]") {
  const LongMacroSteps k(0.02, 480, 10.0);
  REQUIRE(k.H >= 10.0 * k.cut_step);
  REQUIRE(k.H >= 14.0 * k.o.step);
  for (int order : {0, 1, 2}) {
    INFO("extrapolation " << order << ", H = " << k.H << " s, cut joint's stable step " << k.cut_step << " s");
    // Extrapolated values at the cut itself: unstable (extrapolation order 0: far off), with
    // advice that works.
    try {
      const RunSummary r = run_loose(k.m, k.d, k.o, k.options(order, 0.0), nullptr);
      CHECK(order == 0);
      CHECK(k.gap(r.final_state) > 0.1);
    } catch (const RunError& e) {
      const std::string advice = e.what();
      INFO(advice);
      CHECK(order > 0);
      std::smatch match;
      REQUIRE(std::regex_search(advice, match, std::regex("try overlap = ([0-9.e+-]+)")));
      const double suggested = std::stod(match[1]);
      CHECK(suggested == Approx(k.H).epsilon(1e-2));
      LooseStats st;
      const RunSummary advised = run_loose(k.m, k.d, k.o, k.options(order, suggested), nullptr, &st);
      CHECK(k.gap(advised.final_state) < 1e-8);
      CHECK(st.max_position_error < 1e-8);
    }
    // The default overlap: the same.
    CHECK(k.gap(run_loose(k.m, k.d, k.o, k.options(order), nullptr).final_state) < 1e-8);
  }
}

TEST_CASE("overlap: the coupling error falls as the overlap grows, stable even at a quarter of the macro step",
          "[runtime][loose][overlap]") {
  const LongMacroSteps k(0.02, 480, 10.0);
  std::vector<double> gaps;
  for (double fraction : {0.25, 0.5, 0.75, 1.0}) {
    const RunSummary r = run_loose(k.m, k.d, k.o, k.options(1, fraction * k.H), nullptr);
    gaps.push_back(k.gap(r.final_state));
  }
  INFO("gaps " << gaps[0] << " " << gaps[1] << " " << gaps[2] << " " << gaps[3]);
  CHECK(gaps[0] < 0.05);  // 160 links of 0.1 m: bounded, not blown up
  for (std::size_t i = 1; i < gaps.size(); ++i) CHECK(gaps[i] < 0.1 * gaps[i - 1]);
  CHECK(gaps.back() < 1e-9);
}

TEST_CASE("overlap: the energy of an undamped chain stays bounded at macro steps 10x the cut joint's stable step",
          "[runtime][loose][overlap]") {
  LongMacroSteps k(0.0, 4000, 10.0);
  k.m.simulation.output_every = 100;
  k.o = options_from_model(k.m);
  test::MemorySink sink, tight;
  run_loose(k.m, k.d, k.o, k.options(1), &sink);
  run_simulation(k.sys, k.o, &tight);
  REQUIRE(sink.states.size() == 41);
  REQUIRE(tight.states.size() == 41);
  const double e0 = k.sys.energy(k.o.t_start, sink.states.front()).total();
  const double scale = 160 * 1.0 * 9.81 * 160 * 0.1;  // m g L of the whole chain: the energy it can trade
  double drift = 0.0, apart = 0.0;
  for (std::size_t i = 0; i < sink.states.size(); ++i) {
    const double e = k.sys.energy(sink.times[i], sink.states[i]).total();
    drift = std::max(drift, std::abs(e - e0));
    apart = std::max(apart, std::abs(e - k.sys.energy(tight.times[i], tight.states[i]).total()));
  }
  // RK4 at its stable step loses a little energy by itself; the coupling adds nothing to it.
  INFO("largest energy change " << drift << " J of " << scale << " J over " << k.o.t_end << " s; apart from the tight run "
                                << apart << " J");
  CHECK(drift < 1e-2 * scale);
  CHECK(apart < 1e-9 * scale);
}

TEST_CASE("error control: a macro step taken again ends where a run that took the shorter step from the start ends",
          "[runtime][loose][overlap]") {
  const LongMacroSteps k(0.02, 480, 10.0);
  // A quarter macro step of overlap: errors far above a tolerance of 1e-9 m at H, from the
  // first macro step on; it is taken again, shorter.
  LooseOptions lo = k.options(1, 0.25 * k.H);
  lo.coupling_tol = 1e-9;
  LooseStats adaptive;
  run_loose(k.m, k.d, k.o, lo, nullptr, &adaptive);
  INFO(adaptive.macro_steps << " macro steps, " << adaptive.rejected << " taken again, H " << adaptive.smallest_macro_step
                            << " .. " << adaptive.largest_macro_step);
  REQUIRE(adaptive.rejected > 0);
  CHECK(adaptive.over_tolerance == 0);
  CHECK(adaptive.max_position_error <= lo.coupling_tol);
  const CouplingRecord& first = adaptive.records.front();
  REQUIRE(first.t_end - first.t_start < k.H);  // the first macro step was taken again
  // The same first macro step from the start, fixed: the same values at its end, to the
  // bit (the coupling error is measured between the two submodels' states there).
  RunOptions o = k.o;
  o.t_end = first.t_end;
  LooseOptions fixed = lo;
  fixed.coupling_tol = 0.0;
  fixed.macro_step = first.t_end - first.t_start;
  fixed.overlap = 0.25 * k.H;
  LooseStats once;
  run_loose(k.m, k.d, o, fixed, nullptr, &once);
  REQUIRE(once.records.size() == 1);
  CHECK(once.records[0].t_end == first.t_end);
  CHECK(once.records[0].position_error == first.position_error);
  CHECK(once.records[0].velocity_error == first.velocity_error);
}

TEST_CASE("overlap: the train, macro steps of 16 steps and of 10x the couplers' stable step, RK4 or DOPRI5 inside", "[runtime][loose][overlap]") {
  TrainParams t;
  t.wagons = 9;
  Model m = make_train(t);
  RunOptions o = options_from_model(m);
  MultibodySystem sys(m);
  const Eigen::VectorXd tight = run_simulation(sys, o, nullptr).final_state;
  const Decomposition d = decompose(m, 3);
  LooseOptions lo;
  lo.macro_step = 16 * o.step;
  lo.extrapolation = 2;
  const double gap = test::position_gap(sys, run_loose(m, d, o, lo, nullptr).final_state, tight);
  INFO("macro step " << lo.macro_step << " s, gap " << gap << " m");
  CHECK(gap < 1e-6);
  // Ten times the couplers' stable step: far off without an overlap, close with one (which
  // here reaches over the whole train: a disturbance crosses it within a macro step).
  lo.macro_step = std::ceil(10.0 * cut_joint_stable_step(m, d) / o.step) * o.step;
  lo.overlap = 0.0;
  const double without = test::position_gap(sys, run_loose(m, d, o, lo, nullptr).final_state, tight);
  lo.overlap = -1.0;
  const double with = test::position_gap(sys, run_loose(m, d, o, lo, nullptr).final_state, tight);
  INFO("10x the cut joints' stable step, H = " << lo.macro_step << " s: " << without << " m without an overlap, " << with
                                              << " m with");
  CHECK(without > 1e-3);
  CHECK(with < 1e-6);
  // A DOPRI5 submodel between two RK4 ones: as close as the two methods' own errors allow.
  lo.macro_step = 16 * o.step;
  lo.methods = {Method::rk4, Method::dopri5, Method::rk4};
  o.rtol = o.atol = 1e-10;
  CHECK(test::position_gap(sys, run_loose(m, d, o, lo, nullptr).final_state, tight) < 1e-4);
}
