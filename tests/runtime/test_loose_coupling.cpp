// Loose coupling against the tight run: the coupling error falls with the macro step at
// the order the extrapolation promises.
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

using test::position_gap;

// A model run for `steps` steps of a fraction of its stable step (macro steps well inside
// the joints' periods: explicit coupling of stiff joints over longer ones is unstable, as
// in any Jacobi co-simulation), the tight run's end state, and 3 submodels.
struct TightCase {
  Model m;
  double h;
  RunOptions o;
  MultibodySystem sys;
  Eigen::VectorXd tight;
  Decomposition d;
  TightCase(Model model, double fraction, int steps, int output_every)
      : m(std::move(model)), h(fraction * estimate_stable_step(m).step), o(options(m, h, steps, output_every)), sys(m),
        tight(run_simulation(sys, o, nullptr).final_state), d(decompose(m, 3)) {}
  static RunOptions options(Model& m, double h, int steps, int output_every) {
    m.simulation.step = h;
    m.simulation.t_end = m.simulation.t_start + steps * h;
    m.simulation.output_every = output_every;
    return options_from_model(m);
  }
  double gap(const Eigen::VectorXd& y) const { return position_gap(sys, y, tight); }
};

ChainParams chain_of(int bodies) {
  ChainParams c;
  c.bodies = bodies;
  return c;
}

}  // namespace

TEST_CASE("loose coupling converges to the tight run at the extrapolation's order", "[runtime][loose]") {
  TrainParams t;
  t.wagons = 3;
  for (const Model& model : {make_chain(chain_of(24)), make_train(t)}) {
    // every macro step size below divides the output interval of 8 steps
    const TightCase k(model, 0.05, 256, 8);
    const Model& m = k.m;
    const double h = k.h;
    const double expected[3][2] = {{0.7, 1.3}, {1.7, 2.3}, {2.4, 3.4}};  // slopes for orders 0, 1, 2
    for (int order : {0, 1, 2}) {
      std::vector<double> gaps;
      for (int substeps : {8, 4, 2, 1}) {
        LooseOptions lo;
        lo.macro_step = substeps * h;
        lo.extrapolation = order;
        lo.threads = 2;
        LooseStats stats;
        const RunSummary r = run_loose(m, k.d, k.o, lo, nullptr, &stats);
        gaps.push_back(k.gap(r.final_state));
        CHECK(stats.macro_steps == 256 / substeps);
        CHECK(stats.max_position_error > 0.0);  // the submodels really were coupled loosely
      }
      INFO(m.name << ", extrapolation " << order << ": gaps " << gaps[0] << " " << gaps[1] << " " << gaps[2] << " "
                  << gaps[3]);
      for (std::size_t i = 1; i < gaps.size(); ++i) CHECK(gaps[i] < gaps[i - 1]);
      const double slope = std::log2(gaps[2] / gaps[3]);  // the smallest macro steps
      CHECK(slope > expected[order][0]);
      CHECK(slope < expected[order][1]);
    }
  }
}

TEST_CASE("loose coupling: repeatable, DOPRI5 inside submodels, snapshots on the output grid", "[runtime][loose]") {
  ChainParams c;
  c.bodies = 12;
  Model m = make_chain(c);
  const double h = 0.1 * estimate_stable_step(m).step;
  m.simulation.step = h;
  m.simulation.t_end = m.simulation.t_start + 64 * h;
  m.simulation.output_every = 8;
  RunOptions o = options_from_model(m);
  const Decomposition d = decompose(m, 2);
  LooseOptions lo;
  lo.macro_step = 4 * h;
  lo.extrapolation = 2;
  test::MemorySink a, b;
  const RunSummary ra = run_loose(m, d, o, lo, &a);
  lo.threads = 1;
  run_loose(m, d, o, lo, &b);
  REQUIRE(a.states.size() == 9);  // the start and every 8 steps of h
  CHECK(a.times == b.times);
  CHECK(a.states == b.states);  // Jacobi: the same whatever the thread count
  CHECK(ra.final_state == a.states.back());
  // DOPRI5 in each submodel: close to the tight DOPRI5 run.
  o.method = Method::dopri5;
  o.rtol = o.atol = 1e-9;
  MultibodySystem sys(m);
  const Eigen::VectorXd tight = run_simulation(sys, o, nullptr).final_state;
  const RunSummary r = run_loose(m, d, o, lo, nullptr);
  CHECK(position_gap(sys, r.final_state, tight) < 1e-5);
  CHECK(r.evaluations > 0);
  auto changed = [&lo](auto change) {  // lo with one setting changed
    LooseOptions bad = lo;
    change(bad);
    return bad;
  };
  CHECK_THROWS_WITH(run_loose(m, d, o, changed([](LooseOptions& x) { x.macro_step = 0.0; }), nullptr),
                    "macro_step: must be a positive time");
  CHECK_THROWS_WITH(run_loose(m, d, o, changed([](LooseOptions& x) { x.extrapolation = 3; }), nullptr),
                    "extrapolation: must be 0, 1 or 2");
  CHECK_THROWS_WITH(run_loose(m, d, o, changed([](LooseOptions& x) { x.coupling_tol = 1e-6, x.max_lag = 1; }), nullptr),
                    "max_lag: needs a fixed macro step (not with coupling_tol)");
  CHECK_THROWS_WITH(run_loose(m, d, o, changed([](LooseOptions& x) { x.methods = {Method::rk4, Method::dopri5, Method::rk4}; }),
                              nullptr),
                    "methods: one method per submodel: 2 submodels, 3 methods");
}

TEST_CASE("loose coupling: the adaptive macro step keeps the coupling error below the tolerance", "[runtime][loose]") {
  const TightCase k(make_chain(chain_of(24)), 0.05, 512, 64);
  for (int order : {1, 2}) {
    std::vector<double> gaps;
    for (double tol : {1e-8, 1e-9}) {
      LooseOptions lo;
      lo.macro_step = 8 * k.h;  // the first try; too long for these tolerances
      lo.extrapolation = order;
      lo.coupling_tol = tol;
      LooseStats st;
      const RunSummary r = run_loose(k.m, k.d, k.o, lo, nullptr, &st);
      INFO("order " << order << ", tol " << tol << ": " << st.macro_steps << " macro steps, " << st.rejected
                    << " taken again, H " << st.smallest_macro_step << " .. " << st.largest_macro_step);
      CHECK(st.max_position_error <= tol);
      for (double e : st.position_error) CHECK(e <= tol);
      CHECK(st.rejected > 0);
      CHECK(st.smallest_macro_step < st.largest_macro_step);
      gaps.push_back(k.gap(r.final_state));
    }
    // Ten times tighter: the end state ten times closer to the tight run, give or take.
    INFO("order " << order << ": gaps " << gaps[0] << ", " << gaps[1]);
    CHECK(gaps[0] / gaps[1] > 4.0);
    CHECK(gaps[0] / gaps[1] < 25.0);
  }
}

TEST_CASE("loose coupling: the energy of an undamped chain stays bounded at a tenth of the stable step", "[runtime][loose]") {
  ChainParams c;
  c.bodies = 24;
  c.damping_ratio = 0.0;
  Model m = make_chain(c);
  const double h = 0.1 * estimate_stable_step(m).step;  // the CLI's default macro step
  m.simulation.step = h;
  m.simulation.t_end = m.simulation.t_start + 10000 * h;
  m.simulation.output_every = 100;
  const RunOptions o = options_from_model(m);
  LooseOptions lo;
  lo.macro_step = h;
  test::MemorySink sink;
  run_loose(m, decompose(m, 3), o, lo, &sink);
  MultibodySystem sys(m);
  const double e0 = sys.energy(o.t_start, sink.states.front()).total();
  const double scale = 24 * 1.0 * 9.81 * 24 * 0.1;  // m g L of the whole chain: the energy it can trade
  double drift = 0.0;
  for (std::size_t i = 0; i < sink.states.size(); ++i)
    drift = std::max(drift, std::abs(sys.energy(sink.times[i], sink.states[i]).total() - e0));
  INFO("largest energy change " << drift << " J over " << sink.states.size() << " snapshots");
  CHECK(drift < 1e-3 * scale);
}

TEST_CASE("loose coupling with a lag: values L macro steps old, still converging at the extrapolation's order",
          "[runtime][loose]") {
  const TightCase k(make_chain(chain_of(24)), 0.05, 256, 8);
  for (int order : {1, 2}) {
    std::vector<double> lag0, lag1;
    for (int substeps : {4, 2, 1}) {
      for (int lag : {0, 1}) {
        LooseOptions lo;
        lo.macro_step = substeps * k.h;
        lo.extrapolation = order;
        lo.max_lag = lag;
        lo.exact_lag = true;
        (lag ? lag1 : lag0).push_back(k.gap(run_loose(k.m, k.d, k.o, lo, nullptr).final_state));
      }
    }
    INFO("order " << order << ": lag 0 gaps " << lag0[0] << " " << lag0[1] << " " << lag0[2] << "; lag 1 gaps " << lag1[0]
                  << " " << lag1[1] << " " << lag1[2]);
    for (std::size_t i = 0; i < 3; ++i) CHECK(lag1[i] > lag0[i]);  // older values: a larger error
    const double slope = std::log2(lag1[1] / lag1[2]);
    CHECK(slope > order + 0.6);
    CHECK(slope < order + 1.4);
  }
}

TEST_CASE("loose coupling with the newest values: never older than the lag, no worse than the exact lag", "[runtime][loose]") {
  const TightCase k(make_chain(chain_of(24)), 0.05, 256, 8);
  LooseOptions lo;
  lo.macro_step = 2 * k.h;
  lo.extrapolation = 1;
  lo.threads = 2;
  LooseStats synchronous;
  const double gap0 = k.gap(run_loose(k.m, k.d, k.o, lo, nullptr, &synchronous).final_state);
  lo.max_lag = 2;
  lo.exact_lag = true;
  LooseStats exact;
  const double gap_exact = k.gap(run_loose(k.m, k.d, k.o, lo, nullptr, &exact).final_state);
  lo.exact_lag = false;
  for (int run = 0; run < 3; ++run) {
    LooseStats newest;
    const double gap = k.gap(run_loose(k.m, k.d, k.o, lo, nullptr, &newest).final_state);
    INFO("gaps: lag 0 " << gap0 << ", exact lag 2 " << gap_exact << ", newest " << gap << "; largest lag " << newest.largest_lag);
    REQUIRE(newest.records.size() == 128);
    CHECK(newest.largest_lag <= 2);
    CHECK(gap <= 1.5 * gap_exact);
    for (std::size_t i = 0; i < newest.records.size(); ++i) {
      CHECK(newest.records[i].index == static_cast<long>(i) + 1);
      CHECK(newest.records[i].t_end == exact.records[i].t_end);
    }
  }
  // Records: one per macro step, lag 0 without a lag, exactly min(m, 2) with the exact one.
  REQUIRE(synchronous.records.size() == 128);
  CHECK(synchronous.largest_lag == 0);
  CHECK(exact.largest_lag == 2);
  CHECK(exact.lag[0] == 0);
  CHECK(exact.lag[1] == 1);
  CHECK(exact.lag[5] == 2);
  CHECK(exact.max_position_error > synchronous.max_position_error);  // predicted 3 macro steps ahead, not 1
  CHECK(std::abs(synchronous.records.back().t_end - k.o.t_end) < 1e-12);
}

TEST_CASE("loose coupling: a method per submodel", "[runtime][loose]") {
  const TightCase k(make_chain(chain_of(24)), 0.05, 256, 8);
  LooseOptions lo;
  lo.macro_step = 2 * k.h;
  lo.extrapolation = 2;
  RunOptions o = k.o;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  const RunSummary rk4 = run_loose(k.m, k.d, o, lo, nullptr);
  lo.methods = {Method::rk4, Method::dopri5, Method::rk4};
  const RunSummary mixed = run_loose(k.m, k.d, o, lo, nullptr);
  INFO("gaps: rk4 " << k.gap(rk4.final_state) << ", mixed " << k.gap(mixed.final_state));
  CHECK(mixed.evaluations != rk4.evaluations);  // DOPRI5 in the middle took its own steps
  CHECK(k.gap(mixed.final_state) < 10 * k.gap(rk4.final_state));
  CHECK(k.gap(mixed.final_state) < 1e-6);
}
