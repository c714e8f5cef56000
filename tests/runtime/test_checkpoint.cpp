// Checkpoints: a run resumed from any of its checkpoints ends bit for bit as the run that
// was never interrupted, whichever loop wrote the checkpoint (one stepper, or submodels on
// threads) and whatever partition the resumed run has; a loosely coupled run resumed with
// its partition ends as it would have too; a damaged state is refused.
#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/run.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;

namespace {

Model chain_model(Method method) {
  ChainParams chain;
  chain.bodies = 150;
  Model m = make_chain(chain);
  m.simulation.method = method;
  m.simulation.step = 0.5 * estimate_stable_step(m).step;
  m.simulation.t_end = m.simulation.t_start + 64 * *m.simulation.step;
  m.simulation.output_every = 4;
  m.simulation.rtol = m.simulation.atol = 1e-7;
  return m;
}

// Whole (no partition) or k submodels on `threads` threads.
RunPlan plan_for(const Model& m, int k, int threads) {
  RunPlan plan;
  plan.options = options_from_model(m);
  if (k > 0) plan.partition = decompose(m, k);
  plan.parallel.threads = threads;
  return plan;
}

struct Placement {
  int k, threads;
};

}  // namespace

TEST_CASE("a run resumed from any of its checkpoints ends bit for bit as the uninterrupted one", "[runtime][checkpoint]") {
  const std::vector<Placement> placements{{0, 1}, {1, 1}, {3, 2}, {4, 1}};
  for (Method method : {Method::rk4, Method::dopri5}) {
    const Model m = chain_model(method);
    test::MemorySink reference;
    const RunSummary ref = run(m, plan_for(m, 0, 1), &reference);
    REQUIRE(reference.states.size() > 8);
    REQUIRE(reference.states.back() != reference.states.front());
    for (const Placement& writer : placements) {
      INFO(method_name(method) << ", checkpoints written with " << writer.k << " submodels on " << writer.threads << " threads");
      std::vector<std::vector<std::uint8_t>> states;
      Checkpointing write;
      write.every_s = 1e-12;  // at every step (RK4 on submodels: every chunk)
      write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
      RunPlan plan = plan_for(m, writer.k, writer.threads);
      plan.options.checkpoint = &write;
      test::MemorySink full;
      run(m, plan, &full);
      CHECK(test::same_snapshots(full, reference));  // taking checkpoints changes nothing
      REQUIRE(states.size() >= 10);
      for (std::size_t i : {std::size_t{0}, states.size() / 3, states.size() / 2, states.size() - 1})
        for (const Placement& reader : placements) {
          INFO("resumed from checkpoint " << i << " of " << states.size() << " with " << reader.k << " submodels on "
                                          << reader.threads << " threads");
          Checkpointing resume;
          resume.resume = states[i];
          resume.resume_from = "checkpoint " + std::to_string(i);
          RunPlan again = plan_for(m, reader.k, reader.threads);
          again.options.checkpoint = &resume;
          test::MemorySink sink = full;  // holds more snapshots than the checkpoint: the later ones are dropped
          const RunSummary r = run(m, again, &sink);
          CHECK(test::same_snapshots(sink, reference));
          CHECK(r.final_state == ref.final_state);
          CHECK(r.steps == ref.steps);
          CHECK(r.snapshots == ref.snapshots);
        }
    }
  }
}

TEST_CASE("a damaged or foreign checkpoint state is refused before the run starts", "[runtime][checkpoint]") {
  const Model m = chain_model(Method::dopri5);
  std::vector<std::vector<std::uint8_t>> states;
  Checkpointing write;
  write.every_s = 1e-12;
  write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
  RunPlan plan = plan_for(m, 0, 1);
  plan.options.checkpoint = &write;
  run(m, plan, nullptr);
  REQUIRE(!states.empty());
  auto resume_with = [&](std::vector<std::uint8_t> state, Method method) {
    Model other = chain_model(method);
    Checkpointing c;
    c.resume = std::move(state);
    c.resume_from = "checkpoint x";
    RunPlan p = plan_for(other, 0, 1);
    p.options.checkpoint = &c;
    run(other, p, nullptr);
  };
  std::vector<std::uint8_t> cut = states.back();
  cut.resize(cut.size() - 9);
  CHECK_THROWS_WITH(resume_with(cut, Method::dopri5), Catch::Contains("checkpoint x: ends early"));
  CHECK_THROWS_WITH(resume_with(states.back(), Method::rk4), Catch::Contains("the state of a dopri5 run, not of rk4"));
  // A model of another size: its state vector does not fit.
  ChainParams small;
  small.bodies = 10;
  Model other = make_chain(small);
  other.simulation.method = Method::dopri5;
  Checkpointing c;
  c.resume = states.back();
  c.resume_from = "checkpoint y";
  RunPlan p = plan_for(other, 0, 1);
  p.options.checkpoint = &c;
  CHECK_THROWS_WITH(run(other, p, nullptr), Catch::Contains("checkpoint y: a vector of"));
  // A loosely coupled run's numbers depend on its partition: resumed with another, refused.
  Model rk4 = chain_model(Method::rk4);
  RunPlan loose = plan_for(rk4, 3, 1);
  loose.loose = LooseOptions{};
  loose.loose->macro_step = 4 * *rk4.simulation.step;
  states.clear();
  loose.options.checkpoint = &write;
  run(rk4, loose, nullptr);
  REQUIRE(!states.empty());
  c.resume = states.back();
  RunPlan other_cut = plan_for(rk4, 2, 1);
  other_cut.loose = loose.loose;
  other_cut.options.checkpoint = &c;
  CHECK_THROWS_WITH(run(rk4, other_cut, nullptr), Catch::Contains("cut into 3 submodels, not 2"));
  RunPlan tight = plan_for(rk4, 3, 1);
  tight.options.checkpoint = &c;
  CHECK_THROWS_WITH(run(rk4, tight, nullptr), Catch::Contains("checkpoint y"));
}

TEST_CASE("a loosely coupled run resumed from any of its checkpoints ends bit for bit as the uninterrupted one",
          "[runtime][checkpoint][loose]") {
  Model m = chain_model(Method::rk4);
  m.simulation.t_end = m.simulation.t_start + 96 * *m.simulation.step;
  const double H = 4 * *m.simulation.step;
  struct Case {
    std::string name;
    int submodels;
    LooseOptions loose;
  };
  std::vector<Case> cases;
  auto add = [&](std::string name, int k, auto set) {
    LooseOptions lo;
    lo.macro_step = H;
    lo.threads = 2;
    set(lo);
    cases.push_back({std::move(name), k, lo});
  };
  add("rk4 with the automatic overlap", 3, [](LooseOptions&) {});
  add("quadratic extrapolation without overlap", 4, [](LooseOptions& lo) { lo.extrapolation = 2, lo.overlap = 0.0; });
  add("a method per submodel", 3, [](LooseOptions& lo) { lo.methods = {Method::dopri5, Method::rk4, Method::colloc}; });
  add("an exact lag of 1 macro step", 3, [&](LooseOptions& lo) {
    lo.max_lag = 1, lo.exact_lag = true, lo.overlap = 0.0;
    lo.macro_step = *m.simulation.step;  // stable with old neighbour values
  });
  add("an adaptive macro step", 3, [](LooseOptions& lo) { lo.coupling_tol = 1e-9; });
  for (const Case& c : cases) {
    INFO(c.name);
    RunPlan plan = plan_for(m, c.submodels, 2);
    plan.loose = c.loose;
    test::MemorySink reference;
    LooseStats ref_stats;
    const RunSummary ref = run_loose(m, *plan.partition, plan.options, c.loose, &reference, &ref_stats);
    REQUIRE(reference.states.size() > 8);
    REQUIRE(!reference.coupling.empty());
    if (c.loose.coupling_tol > 0.0) CHECK(ref_stats.rejected > 0);  // macro steps taken again, kept across a resume
    std::vector<std::vector<std::uint8_t>> states;
    Checkpointing write;
    write.every_s = 1e-12;  // after every flow-graph run (adaptive: every macro step)
    write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
    plan.options.checkpoint = &write;
    test::MemorySink full;
    run(m, plan, &full);
    CHECK(test::same_snapshots(full, reference));
    CHECK(test::same_records(full.coupling, reference.coupling));
    REQUIRE(states.size() >= 4);
    for (std::size_t i : {std::size_t{0}, states.size() / 2, states.size() - 1}) {
      INFO("resumed from checkpoint " << i << " of " << states.size());
      Checkpointing resume;
      resume.resume = states[i];
      resume.resume_from = "checkpoint " + std::to_string(i);
      RunPlan again = plan;
      again.options.checkpoint = &resume;
      test::MemorySink sink = full;
      LooseStats stats;
      const RunSummary r = run_loose(m, *again.partition, again.options, c.loose, &sink, &stats);
      CHECK(test::same_snapshots(sink, reference));
      CHECK(test::same_records(sink.coupling, reference.coupling));
      CHECK(r.final_state == ref.final_state);
      CHECK(r.steps == ref.steps);
      CHECK(r.evaluations == ref.evaluations);
      CHECK(stats.rejected == ref_stats.rejected);
      CHECK(r.resumed_at.has_value());
    }
  }
}

TEST_CASE("colloc and tirk resumed from any step end bit for bit as the uninterrupted run with every linear solver",
          "[runtime][checkpoint][implicit]") {
  // A stiff chain (translational modes near 2e4 rad/s): Newton matrices kept over several
  // steps, KLU refactorisations on its old pivots, rejected steps.
  ChainParams chain;
  chain.bodies = 12;  // 156 equations: past the dense limit of 100
  chain.stiffness = 1e8;
  Model m = make_chain(chain);
  m.simulation.t_end = m.simulation.t_start + 0.02;
  m.simulation.output_interval = 0.001;
  m.simulation.step.reset();
  m.simulation.rtol = m.simulation.atol = 1e-6;
  struct Case {
    Method method;
    std::string variant, solver, jacobian;
  };
  const std::vector<Case> cases{{Method::colloc, "", "klu", "auto"},         {Method::colloc, "", "sparselu", "auto"},
                                {Method::colloc, "", "banded", "differences"}, {Method::colloc, "2,3", "klu", "auto"},
                                {Method::colloc, "", "dense", "auto"},       {Method::tirk, "", "klu", "auto"},
                                {Method::tirk, "radau5", "sparselu", "auto"}, {Method::tirk, "", "banded", "auto"},
                                {Method::tirk, "radau3,newton-triangular", "klu", "differences"}};
  for (const Case& c : cases) {
    INFO(method_name(c.method) << " " << c.variant << ", " << c.solver << ", Jacobian " << c.jacobian);
    m.simulation.method = c.method;
    m.simulation.variant = c.variant;
    RunPlan plan = plan_for(m, 0, 1);
    plan.options.linear_solver = c.solver;
    plan.options.jacobian = c.jacobian;
    if (c.solver == "dense") {  // the dense path is for small systems: a 6-body chain
      ChainParams few = chain;
      few.bodies = 6;
      Model small = make_chain(few);
      small.simulation = m.simulation;
      m = small;
      plan = plan_for(m, 0, 1);
      plan.options.linear_solver = c.solver;
    }
    test::MemorySink reference;
    const RunSummary ref = run(m, plan, &reference);
    REQUIRE(reference.states.size() > 10);
    REQUIRE(ref.jacobians > 0);
    std::vector<std::vector<std::uint8_t>> states;
    Checkpointing write;
    write.every_s = 1e-12;
    write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
    RunPlan with = plan;
    with.options.checkpoint = &write;
    test::MemorySink full;
    run(m, with, &full);
    CHECK(test::same_snapshots(full, reference));
    REQUIRE(states.size() + 1 == static_cast<std::size_t>(ref.steps));  // one after every step but the last
    for (std::size_t i = 0; i < states.size(); i += std::max<std::size_t>(1, states.size() / 7)) {
      INFO("resumed after step " << i + 1 << " of " << ref.steps);
      Checkpointing resume;
      resume.resume = states[i];
      resume.resume_from = "checkpoint";
      RunPlan again = plan;
      again.options.checkpoint = &resume;
      test::MemorySink sink = full;
      const RunSummary r = run(m, again, &sink);
      CHECK(test::same_snapshots(sink, reference));
      CHECK(r.final_state == ref.final_state);
      CHECK(r.steps == ref.steps);
      CHECK(r.rejected == ref.rejected);
      CHECK(r.jacobians == ref.jacobians);
      CHECK(r.factorizations == ref.factorizations);
    }
  }
}
