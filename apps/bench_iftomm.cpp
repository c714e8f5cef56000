// mbsflow bench iftomm: the IFToMM benchmark problems of examples/models, each run as its
// model file says (method, tolerance) on one thread; the error of the benchmark's point
// against the mechanism's reduced equation in generalised coordinates (integrated with
// RK4 at a step of 1e-4 s), the energy drift and the wall time, beside what published
// entries of other codes report (docs/joints.md gives the sources).
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "bench.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow::cli {
namespace {

struct Problem {
  const char* name;
  const char* file;
  double c, phi0, rate0;       // phi'' = -c cos(phi), the cranks' (or rod's) angle from +x
  Eigen::Vector3d point;       // the benchmark's point on body 0, body frame
  const char* published;       // what other codes report (docs/joints.md)
};

struct Keep : ResultSink {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> y;
  void begin(const MultibodySystem&) override {}
  void write(Snapshot&& s) override {
    t.push_back(s.t);
    y.push_back(std::move(s.state));
  }
  void end() override {}
};

// The reduced pendulum equation as an ODE system for the methods' RK4.
struct Reduced {
  double c;
  Eigen::Index dimension() const { return 2; }
  void rhs(double, const Eigen::VectorXd& s, Eigen::VectorXd& d) const { d << s[1], -c * std::cos(s[0]); }
};

}  // namespace

int bench_iftomm(const BenchArgs& a) {
  const double n = 40.0;
  const Problem problems[] = {
      {"A01 pendulum, 2000 s", "iftomm_a01_pendulum.json", 9.81, std::numbers::pi, 0.0, Eigen::Vector3d::Zero(),
       "OpenSim 3.2: 0.637 s for 10 s (i5-4570)"},
      {"A02 N-four-bar, N=40, 20 s", "iftomm_a02_n_four_bar.json", 9.81 * ((n + 1) / 2 + n) / ((n + 1) / 3 + n),
       std::numbers::pi / 2, -1.0, Eigen::Vector3d(0.5, 0, 0), "OpenSim 3.2: 0.455 s for N=2, 10 s (i5-4570)"},
  };
  BenchCsv csv = open_csv(a);
  csv.out << "problem,method,rtol,steps,error_m,energy_drift_J,wall_s\n";
  std::printf("%-28s %-7s %-8s %8s %11s %11s %8s   %s\n", "problem", "method", "rtol", "steps", "error m", "drift J", "wall s",
              "published");
  for (const Problem& p : problems) {
    const Model m = read_model_file((a.dir == "." ? std::string("examples/models") : a.dir) + "/" + p.file);
    double best = 1e300;
    Keep keep;
    RunSummary summary;
    for (int r = 0; r < a.repeats; ++r) {
      MultibodySystem sys(m);
      keep.t.clear();
      keep.y.clear();
      const auto start = std::chrono::steady_clock::now();
      summary = run_simulation(sys, options_from_model(m), &keep);
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    MultibodySystem sys(m);
    Reduced reduced{p.c};
    Rk4 rk(2);
    Eigen::VectorXd s(2);
    s << p.phi0, p.rate0;
    const double h = 1e-4, e0 = sys.energy(keep.t.front(), keep.y.front()).total();
    double t = 0.0, error = 0.0, drift = 0.0;
    for (std::size_t k = 0; k < keep.t.size(); ++k) {
      for (long i = std::lround((keep.t[k] - t) / h); i > 0; --i, t += h) rk.step(reduced, t, h, s);
      const Eigen::VectorXd& y = keep.y[k];
      const Eigen::Vector4d q = y.segment<4>(sys.layout().orientation(0));
      const Eigen::Vector3d at = y.segment<3>(sys.layout().position(0)) + Eigen::Quaterniond(q[0], q[1], q[2], q[3]) * p.point;
      error = std::max(error, std::hypot(at[0] - std::cos(s[0]), at[1] - std::sin(s[0])));
      drift = std::max(drift, std::abs(sys.energy(keep.t[k], y).total() - e0));
    }
    std::printf("%-28s %-7s %-8.2g %8ld %11.3g %11.3g %8.3f   %s\n", p.name, method_name(m.simulation.method),
                m.simulation.rtol, summary.steps, error, drift, best, p.published);
    csv.out << '"' << p.name << "\"," << method_name(m.simulation.method) << ',' << m.simulation.rtol << ',' << summary.steps
            << ',' << error << ',' << drift << ',' << best << '\n';
  }
  std::printf("wrote %s\n", csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
