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

TEST_CASE("IFToMM A05 moved off its joints by 2e-3 m: the projection puts the governor back without spinning it",
          "[iftomm]") {
  // Implicit steps at tolerance 1e-3 once left the joints this far apart. The projection's
  // Newton iteration with S factored once diverged on such states (the rods turn about
  // their own axes with inertias of 5e-6 kg m^2, so S changes far more than J does), and
  // the velocity projection then spun the rods at 5e5 rad/s; factored at every iterate it
  // converges.
  Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/iftomm_a05_flyball_governor.json");
  m.simulation.t_end = 0.013;
  MultibodySystem sys(m);
  Eigen::VectorXd y = run_simulation(sys, options_from_model(m), nullptr).final_state;
  const StateLayout& l = sys.layout();
  // Every position and orientation moved by up to 2e-3 (m, and radians about each axis).
  for (Eigen::Index i = 0; i < l.bodies; ++i) {
    const double s = (i % 2 == 0 ? 1.0 : -1.0) * 2e-3;
    y.segment<3>(l.position(i)) += Eigen::Vector3d(s, -0.5 * s, 0.7 * s);
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(2e-3, Eigen::Vector3d(1.0, 2.0 - i, 0.5 * i).normalized()));
    const Eigen::Vector4d q = y.segment<4>(l.orientation(i));
    const Eigen::Quaterniond moved = turn * Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    y.segment<4>(l.orientation(i)) << moved.w(), moved.x(), moved.y(), moved.z();
  }
  const double spin_before = y.segment(l.angular_velocity(0), 3 * l.bodies).cwiseAbs().maxCoeff();
  REQUIRE(sys.constraint_violation(0.013, y) > 1e-3);
  sys.after_step(0.013, y);
  CHECK(sys.constraint_violation(0.013, y) < 1e-9);
  CHECK(y.segment(l.angular_velocity(0), 3 * l.bodies).cwiseAbs().maxCoeff() < 2 * spin_before + 1);
}

TEST_CASE("IFToMM A05 with colloc: Newton converges after every projection and the governor stays symmetric",
          "[iftomm]") {
  // The block's f at the last point was kept after the projection moved that point, so
  // the next Jacobian's differences were taken against a stale f and were off by
  // (f(u) - f(u projected)) / delta: Newton failed at nearly every step (1098 steps, 1202
  // rejected in these 0.05 s) and the two rods drifted apart by 1e-3 m.
  Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/iftomm_a05_flyball_governor.json");
  m.simulation.t_end = 0.05;
  RunOptions o = options_from_model(m);
  o.method = Method::colloc;
  o.rtol = o.atol = 1e-3;
  MultibodySystem sys(m);
  RunSummary out;
  REQUIRE_NOTHROW(out = run_simulation(sys, o, nullptr));
  INFO(out.steps << " steps, " << out.rejected << " rejected");
  CHECK(out.steps < 20);
  CHECK(out.rejected <= out.steps);
  CHECK(sys.constraint_violation(o.t_end, out.final_state) < 1e-9);
  // The rods mirror each other through the shaft's axis (x, y, z) -> (-x, -y, z).
  const StateLayout& l = sys.layout();
  const Eigen::Vector3d rod1 = out.final_state.segment<3>(l.position(1)), rod2 = out.final_state.segment<3>(l.position(2));
  CHECK((rod1 + Eigen::Vector3d(rod2.x(), rod2.y(), -rod2.z())).norm() < 1e-6);
}
