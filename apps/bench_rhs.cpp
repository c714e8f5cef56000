// mbsflow bench rhs: nanoseconds per body per right-hand-side evaluation on chain models,
// one thread, with the time split into the three phases of the evaluation; and per body
// per Jacobian, analytic against coloured differences.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include "bench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/jacobian.hpp"

namespace mbsflow::cli {
namespace {

// Repeats f until `seconds` have passed; returns seconds per call.
template <class F>
double time_per_call(double seconds, F f) {
  long calls = 0;
  const auto start = BenchClock::now();
  double elapsed = 0.0;
  do {
    for (int i = 0; i < 4; ++i) f();
    calls += 4;
    elapsed = seconds_since(start);
  } while (elapsed < seconds);
  return elapsed / static_cast<double>(calls);
}

// A state with links bent and moving (deterministic), so that the rotation code takes its
// general branch rather than the small-angle one of the straight initial chain.
Eigen::VectorXd perturbed_state(const MultibodySystem& sys) {
  Eigen::VectorXd y = sys.initial_state();
  const StateLayout& l = sys.layout();
  for (Eigen::Index i = 0; i < l.bodies; ++i) {
    const double a = 0.3 * std::sin(0.7 * static_cast<double>(i));
    y.segment<4>(l.orientation(i)) = Eigen::Vector4d(std::cos(a / 2), 0.3 * std::sin(a / 2), 0.0, std::sin(a / 2)).normalized();
    y.segment<3>(l.velocity(i)) = Eigen::Vector3d(0.1, std::cos(0.3 * static_cast<double>(i)), 0.0);
    y.segment<3>(l.angular_velocity(i)) = Eigen::Vector3d(0.2, -0.1, std::sin(0.5 * static_cast<double>(i)));
  }
  return y;
}

}  // namespace

int bench_rhs(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{2000, 6500, 100000} : a.bodies;
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,evaluations_per_s,ns_per_body_eval,ns_kinematics,ns_joints,ns_bodies,ns_jacobian,ns_differences,colours\n";
  std::printf("right-hand side of generate chain, one thread (ns per body per evaluation; Jacobian: analytic, and by\n"
              "coloured differences, ns per body per Jacobian)\n");
  std::printf("%10s %12s %10s %12s %10s %10s %10s %12s\n", "bodies", "evals/s", "total", "kinematics", "joints", "bodies",
              "jacobian", "differences");
  for (const int n : sizes) {
    ChainParams p;
    p.bodies = n;
    MultibodySystem sys(make_chain(p));
    const Eigen::VectorXd y = perturbed_state(sys);
    Eigen::VectorXd dy(sys.dimension());
    const double s = a.seconds;
    const double total = time_per_call(s, [&] { sys.rhs(0.1, y, dy); });
    const double kin = time_per_call(s / 3, [&] { sys.update_kinematics(0.1, y); });
    const double joints = time_per_call(s / 3, [&] { sys.compute_joint_forces(); });
    const double bodies = time_per_call(s / 3, [&] { sys.compute_derivatives(0.1, y, dy); });
    Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
    const double analytic = time_per_call(s / 3, [&] { sys.jacobian(0.1, y, jac); });
    OdeProblem problem = make_ode_problem("chain", 0.0, 1.0, y, [&](double t, const Eigen::VectorXd& x, Eigen::VectorXd& f) {
      sys.rhs(t, x, f);
    });
    problem.sparsity = jac;
    JacobianEvaluator differences(problem, true);
    sys.rhs(0.1, y, dy);
    long evaluations = 0;
    const double differenced = time_per_call(s / 3, [&] { differences.evaluate(0.1, y, dy, evaluations); });
    const double per = 1e9 / n;
    std::printf("%10d %12.1f %10.1f %12.1f %10.1f %10.1f %10.1f %12.1f (%d colours)\n", n, 1.0 / total, total * per, kin * per,
                joints * per, bodies * per, analytic * per, differenced * per, differences.colours());
    csv << n << ',' << 1.0 / total << ',' << total * per << ',' << kin * per << ',' << joints * per << ',' << bodies * per
        << ',' << analytic * per << ',' << differenced * per << ',' << differences.colours() << '\n';
    if (!dy.allFinite()) throw RunError("benchmark state produced non-finite derivatives");
  }
  std::printf("written to %s\n", csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
