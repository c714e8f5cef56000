// mbsflow bench beams: what elastic beams cost (docs/beams.md).
// 1. Per element and evaluation: a free beam of N elements against a chain of N bushings
//    (mbsflow generate chain), right-hand side and analytic Jacobian, one thread.
// 2. A cantilever of N elements under gravity through RK4 at its stable step and tirk.
// 3. Work-precision of the flexible boom's spin-up (examples/models/flexible_boom.json):
//    the tip's position at the end against a tirk run at 1e-10, tirk and DOPRI5 at a
//    range of tolerances.
#include <cmath>
#include <cstdio>

#include "bench.hpp"
#include "mbsflow/graph/beams.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/run.hpp"

namespace mbsflow::cli {
namespace {

// A 10 m beam of the boom's section (EA = 2.8e7 N, EI = 1.4e4 N m^2, rho A = 1.2 kg/m).
BeamSpec boom_beam(int elements) {
  BeamSpec s;
  s.name = "beam";
  s.points = straight_beam_points({0, 0, 0}, {10, 0, 0}, elements);
  s.E = 2.8e10;
  s.G = 1e10;
  s.density = 1200;
  s.section = {1e-3, 5e-7, 5e-7, 1e-6};
  return s;
}

struct Cost {
  double rhs_ns = 0, jacobian_ns = 0;  // per element (joint) and evaluation
};

Cost cost_per_joint(const Model& m, double seconds) {
  MultibodySystem sys(m);
  const Eigen::VectorXd y = perturbed_state(sys);
  Eigen::VectorXd dy(y.size());
  Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
  const double joints = static_cast<double>(m.joints.size());
  return {1e9 * time_per_call(seconds, [&] { sys.rhs(0.0, y, dy); }) / joints,
          1e9 * time_per_call(seconds, [&] { sys.jacobian(0.0, y, jac); }) / joints};
}

struct BeamOutcome {
  long steps = 0, factorizations = 0;
  double seconds = 0;
  Eigen::VectorXd last;
  std::string note;
};

BeamOutcome run_with(const Model& m, Method method, double tol, double step) {
  RunPlan plan;
  plan.options = options_from_model(m);
  plan.options.method = method;
  plan.options.rtol = plan.options.atol = tol;
  const double span = m.simulation.t_end - m.simulation.t_start;
  if (step > 0) plan.options.step = span / std::ceil(span / step);  // a whole number of steps
  plan.options.output_interval = span;
  KeptStates out;
  BeamOutcome o;
  const auto start = BenchClock::now();
  try {
    const RunSummary s = run(m, plan, &out);
    o.steps = s.steps;
    o.factorizations = s.factorizations;
    o.last = out.y.back();
  } catch (const RunError& e) {
    o.note = e.what();
  }
  o.seconds = seconds_since(start);
  return o;
}

}  // namespace

int bench_beams(const BenchArgs& a) {
  BenchCsv csv = open_csv(a);
  csv.out << "part,case,elements,method,tol,steps,factorizations,seconds,value\n";
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{10000} : a.bodies;
  const double seconds = a.seconds;

  std::printf("1. cost per element and evaluation, one thread (ns)\n%8s %12s %12s %14s %14s %8s\n", "elements", "beam rhs",
              "chain rhs", "beam jacobian", "chain jacobian", "ratio");
  for (int n : sizes) {
    Model beam;
    add_beam(beam, boom_beam(n));
    ChainParams cp;
    cp.bodies = n;
    const Cost b = cost_per_joint(beam, seconds), c = cost_per_joint(make_chain(cp), seconds);
    std::printf("%8d %12.1f %12.1f %14.1f %14.1f %8.2f\n", n, b.rhs_ns, c.rhs_ns, b.jacobian_ns, c.jacobian_ns, b.rhs_ns / c.rhs_ns);
    csv.out << "cost,beam rhs," << n << ",,,,,," << b.rhs_ns << "\ncost,chain rhs," << n << ",,,,,," << c.rhs_ns
            << "\ncost,beam jacobian," << n << ",,,,,," << b.jacobian_ns << "\ncost,chain jacobian," << n << ",,,,,,"
            << c.jacobian_ns << '\n';
  }

  const double t_end = a.t_end > 0 ? a.t_end : 5e-5;
  std::printf("\n2. a cantilever of N elements under gravity over %.3g s\n%8s %-8s %8s %8s %8s %9s  %s\n", t_end, "elements",
              "method", "tol", "steps", "factors", "seconds", "tip deflection (m)");
  for (int n : sizes) {
    Model m;
    add_beam(m, boom_beam(n));
    m.drivers.push_back(Driver{0});
    m.gravity = {0, -9.81, 0};
    m.simulation.t_end = t_end;
    const double stable = estimate_stable_step(m).step;
    const BeamOutcome rk4 = run_with(m, Method::rk4, 0, stable), tirk = run_with(m, Method::tirk, 1e-4, 0);
    for (const auto& [name, tol, o] : {std::tuple{"rk4", 0.0, &rk4}, std::tuple{"tirk", 1e-4, &tirk}}) {
      const double tip = o->last.size() ? o->last[3 * n + 1] : NAN;
      std::printf("%8d %-8s %8.0e %8ld %8ld %9.3f  %.6g %s\n", n, name, tol, o->steps, o->factorizations, o->seconds, tip,
                  o->note.c_str());
      csv.out << "cantilever,," << n << ',' << name << ',' << tol << ',' << o->steps << ',' << o->factorizations << ','
              << o->seconds << ',' << tip << '\n';
    }
  }

  const Model boom = read_model_file(examples_dir(a) + "/flexible_boom.json");
  const int tip_body = static_cast<int>(boom.bodies.size()) - 1;
  const BeamOutcome reference = run_with(boom, Method::tirk, 1e-10, 0);
  if (reference.last.size() == 0) throw RunError("bench beams: the reference run failed: " + reference.note);
  const Eigen::Vector3d tip_ref = reference.last.segment<3>(3 * tip_body);
  std::printf("\n3. the flexible boom's spin-up, tip position at %.3g s against tirk at 1e-10 (%ld steps, %.2f s)\n%-8s %8s %8s %8s %9s %12s\n",
              boom.simulation.t_end, reference.steps, reference.seconds, "method", "tol", "steps", "factors", "seconds", "error (m)");
  const std::vector<double> tols = a.tolerances.empty() ? std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7} : a.tolerances;
  for (Method method : {Method::tirk, Method::dopri5})
    for (double tol : tols) {
      const BeamOutcome o = run_with(boom, method, tol, 0);
      const double error = o.last.size() ? (o.last.segment<3>(3 * tip_body) - tip_ref).norm() : NAN;
      std::printf("%-8s %8.0e %8ld %8ld %9.3f %12.3e %s\n", method_name(method), tol, o.steps, o.factorizations, o.seconds, error,
                  o.note.c_str());
      csv.out << "spin-up,," << boom.bodies.size() - 2 << ',' << method_name(method) << ',' << tol << ',' << o.steps << ','
              << o.factorizations << ',' << o.seconds << ',' << error << '\n';
    }
  std::fprintf(stderr, "mbsflow: wrote %s\n", csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
