// The IFToMM multibody benchmark problems shipped in examples/models, run as a user runs
// them (the model file's own settings), against their reduced equations in generalised
// coordinates integrated independently with a small fixed step: the benchmark's
// tolerance is 1e-3 m on the named point.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

struct Outcome {
  double error = 0.0;   // largest distance of the point from the reference
  double drift = 0.0;   // largest |E - E0|
};

// Runs the example; point(state) is the benchmark's point, reference(phi) where it should be.
template <class Point>
Outcome run_against(const char* file, double c, double phi0, double rate0, Point point) {
  const Model m = read_model_file(std::string(MBSFLOW_EXAMPLES) + "/" + file);
  MultibodySystem sys(m);
  test::MemorySink sink;
  run_simulation(sys, options_from_model(m), &sink);
  const std::vector<double> phi = test::reduced_rk4([c](double p) { return -c * std::cos(p); }, phi0, rate0, sink.times, 1e-4);
  Outcome o;
  const double e0 = sys.energy(sink.times.front(), sink.states.front()).total();
  for (std::size_t k = 0; k < sink.times.size(); ++k) {
    const Eigen::Vector2d p = point(sys, sink.states[k]);
    o.error = std::max(o.error, (p - Eigen::Vector2d(std::cos(phi[k]), std::sin(phi[k]))).norm());
    o.drift = std::max(o.drift, std::abs(sys.energy(sink.times[k], sink.states[k]).total() - e0));
  }
  return o;
}

}  // namespace

TEST_CASE("IFToMM A01: the simple pendulum stays within 1e-3 m of its reference over 2000 s", "[iftomm]") {
  const Outcome o = run_against("iftomm_a01_pendulum.json", 9.81, std::numbers::pi, 0.0,
                                [](const MultibodySystem& s, const Eigen::VectorXd& y) {
                                  return Eigen::Vector2d(y[s.layout().position(0)], y[s.layout().position(0) + 1]);
                                });
  INFO("A01: error " << o.error << " m, energy drift " << o.drift << " J");
  CHECK(o.error < 1e-3);
  CHECK(o.drift < 1e-5);
}

TEST_CASE("IFToMM A02: 40 four-bars pass their singular positions within 1e-3 m of the reference over 20 s", "[iftomm]") {
  // The links stay a parallelogram: M phi'' = -dV/dphi with M = m L^2 ((N+1)/3 + N) and
  // V = m g L ((N+1)/2 + N) sin(phi), phi the cranks' angle from +x.
  const double n = 40.0, c = 9.81 * ((n + 1) / 2 + n) / ((n + 1) / 3 + n);
  const Outcome o = run_against("iftomm_a02_n_four_bar.json", c, std::numbers::pi / 2, -1.0,
                                [](const MultibodySystem& s, const Eigen::VectorXd& y) {
                                  // B0: the top of crank0, 0.5 m along its body x from its centre.
                                  const Eigen::Vector4d q = y.segment<4>(s.layout().orientation(0));
                                  const Eigen::Quaterniond r(q[0], q[1], q[2], q[3]);
                                  const Eigen::Vector3d b = y.segment<3>(s.layout().position(0)) + r * Eigen::Vector3d(0.5, 0, 0);
                                  return Eigen::Vector2d(b[0], b[1]);
                                });
  INFO("A02: error " << o.error << " m, energy drift " << o.drift << " J");
  CHECK(o.error < 1e-3);
  CHECK(o.drift < 1e-2);
}
