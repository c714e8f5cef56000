// The IFToMM multibody benchmark problems shipped in examples/models, run as a user runs
// them (the model file's own settings), against their reduced equations in generalised
// coordinates integrated independently (runtime/src/iftomm_reference.cpp): the
// benchmark's tolerance is 1e-3 m on the named coordinate.
#include <catch2/catch.hpp>

#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/iftomm_reference.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;

namespace {

IftommCheck run_example(IftommProblem p) {
  const IftommInfo& info = iftomm_problems()[static_cast<std::size_t>(p)];
  const Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/" + info.file);
  MultibodySystem sys(m);
  test::MemorySink sink;
  run_simulation(sys, options_from_model(m), &sink);
  const IftommCheck c = check_iftomm(p, sys, sink.times, sink.states);
  INFO(info.title << ": error " << c.error << " m, " << info.drift_of << " drift " << c.drift);
  CHECK(c.error < 1e-3);
  return c;
}

}  // namespace

TEST_CASE("IFToMM A01: the simple pendulum stays within 1e-3 m of its reference over 2000 s", "[iftomm]") {
  CHECK(run_example(IftommProblem::a01_pendulum).drift < 1e-5);
}

TEST_CASE("IFToMM A02: 40 four-bars pass their singular positions within 1e-3 m of the reference over 20 s", "[iftomm]") {
  CHECK(run_example(IftommProblem::a02_n_four_bar).drift < 1e-2);
}

TEST_CASE("IFToMM A05: the stiff flyball governor stays within 1e-3 m of its reference and keeps its spin momentum",
          "[iftomm]") {
  // Nothing turns the shaft: its angular momentum about z (16.05 N m s) is conserved.
  CHECK(run_example(IftommProblem::a05_flyball_governor).drift < 1e-4);
}

TEST_CASE("IFToMM reference: a wrong model misses it", "[iftomm]") {
  // The check can fail: the flyball governor's first 0.5 s with the slider moved 2 mm.
  Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/iftomm_a05_flyball_governor.json");
  m.simulation.t_end = 0.5;
  MultibodySystem sys(m);
  test::MemorySink sink;
  run_simulation(sys, options_from_model(m), &sink);
  const int slider = 3;
  for (Eigen::VectorXd& y : sink.states) y[sys.layout().position(slider) + 2] += 2e-3;
  CHECK(check_iftomm(IftommProblem::a05_flyball_governor, sys, sink.times, sink.states).error > 1e-3);
}

TEST_CASE("IFToMM A05 after colloc's steps at tolerance 1e-3: every projection puts the governor back on its joints",
          "[iftomm]") {
  // These steps leave the joints up to 2e-3 m apart. The projection's Newton iteration with
  // S factored once diverged here (t = 0.013 s), and the velocity projection then spun the
  // rods at 5e5 rad/s; factored at every iterate it converges.
  Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/iftomm_a05_flyball_governor.json");
  m.simulation.t_end = 0.05;
  RunOptions o = options_from_model(m);
  o.method = Method::colloc;
  o.rtol = o.atol = 1e-3;
  MultibodySystem sys(m);
  test::MemorySink sink;
  RunSummary out;
  REQUIRE_NOTHROW(out = run_simulation(sys, o, &sink));
  CHECK(sys.constraint_violation(o.t_end, out.final_state) < 1e-9);
  double spin = 0;
  for (const Eigen::VectorXd& y : sink.states)
    spin = std::max(spin, y.segment(sys.layout().angular_velocity(0), 3 * sys.layout().bodies).cwiseAbs().maxCoeff());
  CHECK(spin < 10.0);  // the shaft starts at 2 pi rad/s
}
