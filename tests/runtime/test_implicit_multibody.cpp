// The implicit methods on multibody models. They evaluate their stages from several
// flow-graph nodes at once: on a whole model each on a copy of the system, on a loosely
// coupled submodel in turns on its one scratch. Neither may race or change a number: the
// same run gives the same numbers every time and on any thread count. Their order with fixed steps, the energy of an undamped
// stiff chain, and the message when the iteration cannot go on.
#include <catch2/catch.hpp>

#include <cmath>

#include "mbsflow/line_fit.hpp"
#include "mbsflow/graph/force_element.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/methods/shifted_solver.hpp"
#include "mbsflow/runtime/eliminable.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "reference_run.hpp"
#include "test_support.hpp"

using namespace mbsflow;

TEST_CASE("colloc and tirk on a multibody model give the same numbers every run and on any thread count", "[runtime][implicit]") {
  ChainParams chain;
  chain.bodies = 10;
  const Model m = make_chain(chain);
  for (Method method : {Method::colloc, Method::tirk}) {
    RunOptions o = options_from_model(m);
    o.method = method;
    o.t_end = o.t_start + 0.005;
    o.output_interval = 0.0005;
    std::vector<Eigen::VectorXd> first;
    // Each thread count twice: with more than one, stages run on copies of the system.
    for (int run = 0; run < 6; ++run) {
      o.threads = 1 + run / 2;
      MultibodySystem sys(m);
      test::MemorySink sink;
      run_simulation(sys, o, &sink);
      REQUIRE(sink.states.size() == 11);
      REQUIRE(sink.states.back() != sink.states.front());
      INFO(method_name(method) << ", run " << run << ", threads " << o.threads);
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


TEST_CASE("tirk on a stiff chain: analytic and coloured-difference Jacobians, KLU and SparseLU agree, and the dense output "
          "matches DOPRI5",
          "[runtime][implicit][sparse]") {
  ChainParams chain;
  chain.bodies = 40;  // 520 equations: the sparse path
  chain.stiffness = 1e8;  // translational modes near 2e4 rad/s
  const Model m = make_chain(chain);
  MultibodySystem sys(m);
  REQUIRE(sys.has_analytic_jacobian());
  RunOptions o = options_from_model(m);
  const test::MemorySink reference = test::dopri5_reference(sys, o);
  std::vector<test::MemorySink> runs(3);
  std::vector<RunSummary> summaries;
  for (const auto& [solver, jacobian] : {std::pair{"klu", "auto"}, {"sparselu", "auto"}, {"klu", "differences"}}) {
    o.linear_solver = solver;
    o.jacobian = jacobian;
    summaries.push_back(run_simulation(sys, o, &runs[summaries.size()]));
  }
  for (const RunSummary& s : summaries) {
    INFO(s.steps << " steps, " << s.jacobians << " Jacobians, " << s.factorizations << " factorisations, " << s.evaluations
                 << " evaluations");
    CHECK(s.jacobians > 0);
    CHECK(s.factorizations >= s.jacobians);
    // The iteration's own contraction rate does not call for a new Jacobian: it is kept
    // over several steps (it was renewed at almost every step before).
    CHECK(s.jacobians * 4 < s.steps);
  }
  // Differencing by colour: far fewer evaluations per Jacobian than the 520 columns; the
  // analytic Jacobian needs none.
  const RunSummary& fd = summaries[2];
  CHECK(fd.evaluations < 100 * (fd.jacobians + fd.steps));
  CHECK(summaries[0].evaluations < fd.evaluations);
  REQUIRE(runs[0].states.size() == reference.states.size());
  double gap = 0.0, solvers = 0.0, jacobians = 0.0;
  for (std::size_t k = 0; k < reference.states.size(); ++k) {
    gap = std::max(gap, test::position_gap(sys, runs[0].states[k], reference.states[k]));
    gap = std::max(gap, test::position_gap(sys, runs[2].states[k], reference.states[k]));
    solvers = std::max(solvers, (runs[0].states[k] - runs[1].states[k]).cwiseAbs().maxCoeff());
    jacobians = std::max(jacobians, (runs[0].states[k] - runs[2].states[k]).cwiseAbs().maxCoeff());
  }
  CHECK(gap < 1e-5);
  CHECK(solvers < 1e-6);    // roundoff apart, within the run's tolerance
  // The differenced Jacobian is dear here (dozens of coloured columns): after an iteration
  // fails with an old one, that run shortens its steps where the analytic one renews its
  // Jacobian, so the two agree within the runs' tolerance (1e-6), not to the iteration's.
  CHECK(jacobians < 1e-5);
  o.jacobian = "exact";
  CHECK_THROWS_WITH(run_simulation(sys, o, nullptr), Catch::Contains("auto (analytic where the model has one) or differences"));
  o.jacobian = "auto";
  o.linear_solver = "lu";
  CHECK_THROWS_WITH(run_simulation(sys, o, nullptr), Catch::Contains("unknown linear solver 'lu'"));
}

namespace {

// Final state of a fixed-step run of `method` with `steps` steps over the model's span.
Eigen::VectorXd fixed_step_end(const Model& m, Method method, const std::string& variant, int steps) {
  RunOptions o = options_from_model(m);
  o.method = method;
  o.variant = variant;
  o.fixed_step = true;
  o.step = (o.t_end - o.t_start) / steps;
  o.rtol = o.atol = 1e-13;  // the iterations converge to rounding
  o.threads = 1;
  MultibodySystem sys(m);
  return run_simulation(sys, o, nullptr).final_state;
}

}  // namespace

TEST_CASE("tirk on a chain of stiff compliant revolute joints: the analytic Jacobian saves evaluations and agrees within the tolerance",
          "[runtime][implicit][sparse]") {
  ChainParams chain;
  chain.bodies = 40;
  chain.stiffness = 1e8;  // on each of the joint's constrained directions
  Model m = make_chain(chain);
  for (Joint& j : m.joints) {
    j.type = JointType::revolute;
    j.rigid = false;
  }
  MultibodySystem sys(m);
  REQUIRE(sys.has_analytic_jacobian());
  RunOptions o = options_from_model(m);
  const test::MemorySink reference = test::dopri5_reference(sys, o);
  test::MemorySink exact, differenced;
  o.jacobian = "auto";
  const RunSummary a = run_simulation(sys, o, &exact);
  o.jacobian = "differences";
  const RunSummary d = run_simulation(sys, o, &differenced);
  INFO("analytic: " << a.steps << " steps, " << a.jacobians << " Jacobians, " << a.evaluations
                    << " evaluations; differences: " << d.steps << " steps, " << d.jacobians << " Jacobians, " << d.evaluations);
  CHECK(a.evaluations < d.evaluations);
  REQUIRE(exact.states.size() == reference.states.size());
  REQUIRE(differenced.states.size() == reference.states.size());
  double gap = 0.0, jacobians = 0.0;
  for (std::size_t k = 0; k < reference.states.size(); ++k) {
    gap = std::max(gap, test::position_gap(sys, exact.states[k], reference.states[k]));
    jacobians = std::max(jacobians, (exact.states[k] - differenced.states[k]).cwiseAbs().maxCoeff());
  }
  CHECK(gap < 1e-5);
  CHECK(jacobians < 1e-5);  // different steps after a failed iteration (above): within the runs' tolerance
}

TEST_CASE("implicit methods show their order on a multibody chain with fixed steps", "[runtime][implicit][order]") {
  ChainParams chain;
  chain.bodies = 4;
  chain.stiffness = 1e3;  // joint modes near 90 rad/s: resolved by the steps below
  Model m = make_chain(chain);
  m.simulation.t_end = 0.2;
  RunOptions ro = options_from_model(m);
  ro.method = Method::dopri5;
  ro.rtol = ro.atol = 1e-13;
  MultibodySystem sys(m);
  const Eigen::VectorXd reference = run_simulation(sys, ro, nullptr).final_state;
  struct Case {
    Method method;
    const char* variant;
    double order;
    std::vector<int> steps;
  };
  // Radau IIA with 3 and 2 stages (orders 5 and 3), by the full and the triangular Newton
  // iteration; the 2-point collocation block, whose block end is superconvergent (order 4).
  const std::vector<Case> cases = {{Method::tirk, "radau3", 5, {20, 40, 80}},
                                   {Method::tirk, "radau3,newton-triangular", 5, {20, 40, 80}},
                                   {Method::tirk, "radau2", 3, {40, 80, 160}},
                                   {Method::colloc, "1,2", 4, {80, 160, 320}}};
  for (const Case& c : cases) {
    std::vector<double> h, e;
    for (int n : c.steps) {
      h.push_back(0.2 / n);
      e.push_back(test::position_gap(sys, fixed_step_end(m, c.method, c.variant, n), reference));
    }
    const double slope = log_log_slope(h, e);
    INFO(method_name(c.method) << " " << c.variant << ": errors " << e[0] << ", " << e[1] << ", " << e[2] << ", slope " << slope);
    CHECK(std::abs(slope - c.order) < 0.3);
  }
  RunOptions bad = ro;
  bad.fixed_step = true;
  CHECK_THROWS_WITH(run_simulation(sys, bad, nullptr), Catch::Contains("for colloc and tirk, not dopri5"));
}

TEST_CASE("tirk keeps the energy of an undamped stiff chain bounded", "[runtime][implicit][energy]") {
  ChainParams chain;
  chain.bodies = 20;
  Model m = make_chain(chain);
  for (Joint& j : m.joints) set_bushing_from_frequency(m, j, 1e4, 0.0);  // no damping at all
  RunOptions o = options_from_model(m);
  o.method = Method::tirk;
  o.t_end = o.t_start + 0.3;
  o.output_interval = 0.01;
  o.rtol = o.atol = 1e-5;
  MultibodySystem sys(m);
  test::MemorySink sink;
  const RunSummary s = run_simulation(sys, o, &sink);
  REQUIRE(sink.states.size() == 31);
  const double e0 = sys.energy(o.t_start, sink.states.front()).total();
  double highest = e0, lowest = e0, scale = 0;
  for (std::size_t k = 0; k < sink.states.size(); ++k) {
    const Energy e = sys.energy(sink.times[k], sink.states[k]);
    highest = std::max(highest, e.total());
    lowest = std::min(lowest, e.total());
    scale = std::max(scale, e.kinetic);
  }
  INFO(s.steps << " steps; energy from " << lowest - e0 << " to " << highest - e0 << " J around E0, kinetic up to " << scale);
  REQUIRE(scale > 1.0);  // the chain does swing
  // Radau IIA is algebraically stable: no growth, and at this tolerance little loss.
  CHECK(highest - e0 < 1e-4 * scale);
  CHECK(e0 - lowest < 1e-2 * scale);
}

namespace {

// A force that becomes NaN on one body after t = 0.01 s: no step can pass it.
struct Poison final : ForceElement {
  int body;
  explicit Poison(int b) : body(b) {}
  std::vector<int> bodies() const override { return {body}; }
  void evaluate(double t, const Kinematics&, std::span<Wrench> out) const override {
    out[0].force = Eigen::Vector3d(0, t > 0.01 ? std::nan("") : 0.0, 0);
  }
};

}  // namespace

TEST_CASE("tirk refuses a model on which its iteration keeps failing and names the body", "[runtime][implicit][failure]") {
  ChainParams chain;
  chain.bodies = 6;
  const Model m = make_chain(chain);
  MultibodySystem sys(m);
  sys.add_force_element(std::make_shared<Poison>(3));
  RunOptions o = options_from_model(m);
  o.method = Method::tirk;
  o.t_end = o.t_start + 0.05;
  CHECK_THROWS_WITH(run_simulation(sys, o, nullptr),
                    Catch::Contains("step size underflow") && Catch::Contains("the iteration failed") &&
                        Catch::Contains("the velocity (y) of body 'link3' (joints, stiffest first, 'j3', 'j4')"));
}

namespace {

Model a05() { return read_model_file(std::string(MBSFLOW_EXAMPLES) + "/iftomm_a05_flyball_governor.json"); }

// tirk on one thread over A05's first 3 s; `reference` gets that run at tol 1e-8.
RunOptions a05_first_seconds(const Model& m, MultibodySystem& sys, RunSummary& reference) {
  RunOptions o = options_from_model(m);
  o.method = Method::tirk;
  o.threads = 1;
  o.t_end = o.t_start + 3.0;
  o.rtol = o.atol = 1e-8;
  reference = run_simulation(sys, o, nullptr);
  return o;
}

// `method` at tol 1e-4 over A05's first 3 s, and its final positions' gap to the reference.
struct A05Run {
  RunSummary run;
  double gap = 0;
};
A05Run a05_at_tol_1e4(Method method) {
  const Model m = a05();
  MultibodySystem sys(m);
  RunSummary reference;
  RunOptions o = a05_first_seconds(m, sys, reference);
  o.method = method;
  o.rtol = o.atol = 1e-4;
  A05Run r{run_simulation(sys, o, nullptr)};
  r.gap = test::position_gap(sys, r.run.final_state, reference.final_state);
  return r;
}

}  // namespace

TEST_CASE("tirk on A05, whose Jacobian renewals are dear, shortens its steps rather than renew a Jacobian at each",
          "[runtime][implicit]") {
  // A05's stiff couplers outrun a Jacobian in about 40 ms. Renewing one at every step for a
  // while after an iteration failed with an old one took 137 Jacobians in 198 steps over
  // these 3 s (differenced); the steps are now kept below the one that failed, and a
  // Jacobian lasts several of them. Renewals are dear both ways: the pattern's 52 colours
  // are 52 right-hand sides by differences, and the analytic Jacobian costs about 22.
  const Model m = a05();
  MultibodySystem sys(m);
  REQUIRE(sys.has_analytic_jacobian());  // through the rigid cluster's reactions
  RunSummary reference;
  RunOptions o = a05_first_seconds(m, sys, reference);
  o.rtol = o.atol = 1e-4;
  for (const char* jacobian : {"auto", "differences"}) {
    o.jacobian = jacobian;
    const RunSummary run = run_simulation(sys, o, nullptr);
    INFO(jacobian << ": " << run.steps << " steps, " << run.jacobians << " Jacobians, " << run.evaluations << " evaluations");
    CHECK(run.jacobians * 3 < run.steps);
    CHECK(test::position_gap(sys, run.final_state, reference.final_state) < 1e-3);  // m, in a mechanism half a metre across
  }

  // Fixed steps cannot be shortened: after a failed iteration they keep renewing the
  // Jacobian for a while, as on a model with cheap Jacobians, and the run goes through.
  o.jacobian = "auto";
  o.rtol = o.atol = 1e-6;
  o.fixed_step = true;
  o.step = 0.01;
  const RunSummary fixed = run_simulation(sys, o, nullptr);
  INFO("fixed steps: " << fixed.steps << " steps, " << fixed.rejected << " rejected, " << fixed.jacobians << " Jacobians");
  CHECK(fixed.rejected * 10 < fixed.steps);
}

TEST_CASE("tirk on A05 retries a step whose old Jacobian failed from its predictor, not from the step's start",
          "[runtime][implicit]") {
  // The old Jacobian failed, not the guess: the retry with a fresh one at the same step
  // starts from the last step's extrapolated collocation polynomial. Restarting from
  // Y_i = x took 4 or 5 iterations in every retry: over these 3 s at tol 1e-4, 15.1
  // right-hand sides a step (4683 in 310 steps) against 13.2 from the predictor.
  const auto [run, gap] = a05_at_tol_1e4(Method::tirk);
  INFO(run.steps << " steps, " << run.rejected << " rejected, " << run.evaluations << " evaluations, gap " << gap << " m");
  REQUIRE(run.rejected * 10 > run.steps);  // the case at hand: retries after an old Jacobian failed
  CHECK(run.evaluations < 14 * run.steps);
  CHECK(gap < 1e-3);
}

TEST_CASE("colloc on A05 grows its steps slowly after a fresh Jacobian failed instead of doubling back into the failure",
          "[runtime][implicit]") {
  // The error lets A05's blocks grow fourfold, but its stiff couplers stop the iteration
  // at about twice the step that converged: halving and growing back failed at every
  // other block (422 rejections in 624 blocks over the model's 10 s at tol 1e-4).
  const auto [run, gap] = a05_at_tol_1e4(Method::colloc);
  INFO(run.steps << " blocks, " << run.rejected << " rejected, " << run.evaluations << " evaluations, gap " << gap << " m");
  CHECK(run.rejected * 3 < run.steps);
  CHECK(gap < 1e-3);
}

TEST_CASE("tirk variants name a tableau and an iteration, in any order", "[runtime][implicit]") {
  ChainParams chain;
  chain.bodies = 5;
  Model m = make_chain(chain);
  m.simulation.t_end = 0.05;
  MultibodySystem sys(m);
  RunOptions o = options_from_model(m);
  o.method = Method::tirk;
  o.rtol = o.atol = 1e-6;
  o.threads = 1;
  std::vector<Eigen::VectorXd> ends;
  for (const char* v : {"", "radau3,newton", "newton,radau3", "radau5", "newton-triangular"}) {
    o.variant = v;
    ends.push_back(run_simulation(sys, o, nullptr).final_state);
  }
  CHECK((ends[0].array() == ends[1].array()).all());  // the default is radau3 with the full Newton iteration
  CHECK((ends[1].array() == ends[2].array()).all());
  for (const Eigen::VectorXd& e : ends) CHECK((e - ends[0]).cwiseAbs().maxCoeff() < 1e-4);
  o.variant = "radau3,newtn";
  CHECK_THROWS_WITH(run_simulation(sys, o, nullptr), Catch::Contains("names neither a tableau nor an iteration: 'newtn'"));
}

TEST_CASE("without a step in the model, tirk picks its first step from the tolerances, not the RK4 limit",
          "[runtime][implicit]") {
  ChainParams chain;
  chain.bodies = 10;
  Model m = make_chain(chain);
  for (Joint& j : m.joints) set_bushing_from_frequency(m, j, 1e5, 0.02);
  m.simulation.t_end = m.simulation.t_start + 0.02;
  m.simulation.output_interval = 0.001;
  m.simulation.method = Method::tirk;
  RunOptions o = options_from_model(m);
  REQUIRE_FALSE(o.step_given);
  o.rtol = o.atol = 1e-3;
  MultibodySystem sys(m);
  const RunSummary own = run_simulation(sys, o, nullptr);
  o.step_given = true;  // start from the RK4 stability estimate, as before
  const RunSummary from_rk4 = run_simulation(sys, o, nullptr);
  INFO(own.steps << " steps from its own first step, " << from_rk4.steps << " from the RK4 estimate " << o.step << " s");
  CHECK(own.steps < from_rk4.steps);  // 32 against 44 when written
}

TEST_CASE("the Newton matrices of multibody models eliminate positions and quaternions first", "[runtime][implicit][sparse]") {
  ChainParams chain;
  chain.bodies = 30;
  TrainParams train;
  train.wagons = 6;
  std::vector<std::pair<std::string, Model>> models{{"chain", make_chain(chain)}, {"train", make_train(train)}};
  for (const char* file : {"slider_crank.json", "iftomm_a05_flyball_governor.json", "features.json", "lead_screw.json"})
    models.emplace_back(file, read_model_file(std::string(MBSFLOW_EXAMPLES) + "/" + file));
  for (const auto& [name, m] : models) {
    INFO(name);
    MultibodySystem sys(m);
    Eigen::SparseMatrix<double> j = sys.jacobian_pattern();
    if (sys.has_analytic_jacobian()) sys.jacobian(0.0, sys.initial_state(), j);
    ShiftedSolver<std::complex<double>> full, reduced;
    reduced.eliminate_first(make_elimination(eliminable_unknowns(sys.layout())));
    const std::complex<double> gamma(2e-3, 1e-3);
    full.factorize(j, gamma, LinearSolverKind::klu);
    reduced.factorize(j, gamma, LinearSolverKind::klu);
    CHECK(reduced.reduced());  // rigid clusters and force elements leave the kinematic rows alone
    Eigen::VectorXcd b = Eigen::VectorXcd::LinSpaced(j.rows(), 1.0, 2.0), x = b;
    full.solve(b);
    reduced.solve(x);
    CHECK((x - b).cwiseAbs().maxCoeff() <= 1e-10 * b.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("the lead screw example moves its carriage by the pitch per turn, explicitly and implicitly", "[runtime][implicit]") {
  // The shaft turns once a second; the carriage, held from turning, goes -5 mm per turn.
  const Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/lead_screw.json");
  for (Method method : {Method::rk4, Method::dopri5, Method::tirk}) {
    INFO(method_name(method));
    RunOptions o = options_from_model(m);
    o.method = method;
    o.rtol = o.atol = 1e-8;
    MultibodySystem sys(m);
    test::MemorySink sink;
    const RunSummary s = run_simulation(sys, o, &sink);
    REQUIRE(sink.states.size() == 201);
    for (std::size_t k = 0; k < sink.states.size(); ++k) {
      const double t = sink.times[k];
      CHECK(sink.states[k][sys.layout().position(1)] == Approx(-0.005 * t).margin(1e-11));
      CHECK(sys.constraint_violation(t, sink.states[k]) < 1e-10);
    }
    CHECK(s.final_state[sys.layout().angular_velocity(0)] == Approx(2.0 * M_PI).epsilon(1e-9));
  }
}
