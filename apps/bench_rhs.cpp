// mbsflow bench rhs: nanoseconds per body per right-hand-side evaluation on chain models,
// one thread, with the time split into the three phases of the evaluation; and per body
// per Jacobian, analytic against coloured differences. Then the same for the examples with
// rigid joints, whose clusters make differences dear.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "bench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/graph/simd.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/methods/jacobian.hpp"

namespace mbsflow::cli {
namespace {

// The machine side of the roofline, on one thread: the STREAM triad's bandwidth (a = b +
// s c over arrays far larger than the caches; 24 bytes an element, as STREAM counts) and
// the multiply-add throughput of independent chains, as this build compiles them (its
// instruction set, without -march), in operations per ns. Best of 3 each.
struct MachineRoof {
  double triad_gb_s = 0.0;
  double peak_gflop_s = 0.0;
};

MachineRoof measure_machine() {
  MachineRoof roof;
  const std::size_t n = std::size_t{1} << 23;  // 64 MB per array
  std::vector<double> x(n, 1.0), b(n, 2.0), c(n, 0.5);
  for (int r = 0; r < 3; ++r) {
    const auto start = BenchClock::now();
    const double s = 1.0 + 1e-3 * r;
    double* out = x.data();
    const double *pb = b.data(), *pc = c.data();
    for (std::size_t i = 0; i < n; ++i) out[i] = pb[i] + s * pc[i];
    roof.triad_gb_s = std::max(roof.triad_gb_s, 24.0 * static_cast<double>(n) / seconds_since(start) / 1e9);
  }
  // Independent chains in Eigen packets: packed instructions of the build's instruction
  // set (SSE2 for x86-64 without -march), enough chains to cover the latency.
  constexpr int chains = 16;
  const long rounds = 20'000'000;
  for (int r = 0; r < 3; ++r) {
    Eigen::Array<double, chains, 1> acc = Eigen::Array<double, chains, 1>::LinSpaced(1.0, 1.1) + x[static_cast<std::size_t>(r)];
    const double m = 0.999999, add = 1e-7;
    const auto start = BenchClock::now();
    for (long i = 0; i < rounds; ++i) acc = acc * m + add;
    const double seconds = seconds_since(start);
    if (!acc.allFinite()) throw RunError("bench rhs: the peak loop went non-finite");
    roof.peak_gflop_s = std::max(roof.peak_gflop_s, 2.0 * chains * static_cast<double>(rounds) / seconds / 1e9);
  }
  return roof;
}

// Seconds per Jacobian of sys at (t, y) by coloured differences along jac's pattern; the
// colours to *colours.
double differenced_seconds(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const Eigen::SparseMatrix<double>& jac,
                           double seconds, int* colours) {
  OdeProblem problem = make_ode_problem("model", 0.0, 1.0, y, [&](double time, const Eigen::VectorXd& x, Eigen::VectorXd& f) {
    sys.rhs(time, x, f);
  });
  problem.sparsity = jac;
  JacobianEvaluator differences(problem, true);
  Eigen::VectorXd dy(sys.dimension());
  sys.rhs(t, y, dy);
  long evaluations = 0;
  *colours = differences.colours();
  return time_per_call(seconds, [&] { differences.evaluate(t, y, dy, evaluations); });
}

// The examples with rigid joints: microseconds per right-hand side and per Jacobian
// (analytic through the clusters' reactions, and by coloured differences) at the initial
// state, one thread; to `path` as CSV.
void rigid_models(const BenchArgs& a, const std::string& path) {
  const std::vector<const char*> files{"slider_crank.json", "iftomm_a05_flyball_governor.json", "iftomm_a02_n_four_bar.json"};
  if (!std::filesystem::exists(examples_dir(a) + "/" + files.front())) {
    std::printf("\nexamples with rigid joints: not in %s (run from the source folder, or give --dir)\n", examples_dir(a).c_str());
    return;
  }
  std::ofstream csv(path);
  if (!csv) throw InputError("cannot write " + path);
  csv << "model,bodies,equations,us_rhs,us_jacobian,us_differences,colours\n";
  std::printf("\nexamples with rigid joints, one thread, initial state (microseconds per call)\n");
  std::printf("%-32s %7s %9s %10s %12s %14s %8s\n", "model", "bodies", "equations", "rhs", "jacobian", "differences", "colours");
  for (const char* file : files) {
    MultibodySystem sys(read_model_file(examples_dir(a) + "/" + file));
    const Eigen::VectorXd y = sys.initial_state();
    Eigen::VectorXd dy(sys.dimension());
    const double s = a.seconds;
    const double rhs = time_per_call(s, [&] { sys.rhs(0.0, y, dy); });
    Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
    const double analytic = time_per_call(s, [&] { sys.jacobian(0.0, y, jac); });
    int colours = 0;
    const double differenced = differenced_seconds(sys, 0.0, y, jac, s, &colours);
    std::printf("%-32s %7ld %9ld %10.1f %12.1f %14.1f %8d\n", file, static_cast<long>(sys.layout().bodies),
                static_cast<long>(sys.dimension()), rhs * 1e6, analytic * 1e6, differenced * 1e6, colours);
    csv << file << ',' << sys.layout().bodies << ',' << sys.dimension() << ',' << rhs * 1e6 << ',' << analytic * 1e6 << ','
        << differenced * 1e6 << ',' << colours << '\n';
  }
  std::printf("written to %s\n", path.c_str());
}

}  // namespace

int bench_rhs(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{2000, 6500, 100000} : a.bodies;
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,evaluations_per_s,ns_per_body_eval,ns_kinematics,ns_joints,ns_bodies,ns_jacobian,ns_differences,colours,"
         "bytes_per_body,compiled_bytes_per_body,workspace_bytes_per_body,achieved_GB_s,triad_GB_s,peak_GFLOP_s,simd\n";
  const MachineRoof roof = measure_machine();
  struct Row {
    int bodies;
    double ns, bytes, compiled, workspace;
  };
  std::vector<Row> rows;
  std::printf("right-hand side of generate chain, one thread, lane kernels on %s (ns per body per evaluation;\n"
              "Jacobian: analytic, and by coloured differences, ns per body per Jacobian; MBSFLOW_SIMD=sse2 keeps SSE2)\n",
              simd() == Simd::avx ? "AVX, 4 lanes" : "SSE2, 2 lanes");
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
    const MultibodySystem::MemoryUse use = sys.memory_use();  // before the Jacobian's scratch is made
    const double kin = time_per_call(s / 3, [&] { sys.kinematics_for_rhs(0.1, y); });
    const double joints = time_per_call(s / 3, [&] { sys.compute_joint_forces(); });
    const double bodies = time_per_call(s / 3, [&] { sys.compute_derivatives(0.1, y, dy); });
    Eigen::SparseMatrix<double> jac = sys.jacobian_pattern();
    const double analytic = time_per_call(s / 3, [&] { sys.jacobian(0.1, y, jac); });
    int colours = 0;
    const double differenced = differenced_seconds(sys, 0.1, y, jac, s / 3, &colours);
    sys.rhs(0.1, y, dy);
    const double per = 1e9 / n;
    std::printf("%10d %12.1f %10.1f %12.1f %10.1f %10.1f %10.1f %12.1f (%d colours)\n", n, 1.0 / total, total * per, kin * per,
                joints * per, bodies * per, analytic * per, differenced * per, colours);
    // What one evaluation streams per body: the state read and the derivative written, the
    // compiled model read, the workspace written and read back.
    const double compiled = static_cast<double>(use.compiled) / n, workspace = static_cast<double>(use.workspace) / n;
    const double bytes = 2.0 * static_cast<double>(sys.dimension()) * sizeof(double) / n + compiled + 2.0 * workspace;
    rows.push_back({n, total * per, bytes, compiled, workspace});
    csv << n << ',' << 1.0 / total << ',' << total * per << ',' << kin * per << ',' << joints * per << ',' << bodies * per
        << ',' << analytic * per << ',' << differenced * per << ',' << colours << ',' << bytes << ',' << compiled
        << ',' << workspace << ',' << bytes / (total * per) << ',' << roof.triad_gb_s << ',' << roof.peak_gflop_s << ','
        << (simd() == Simd::avx ? "avx" : "sse2") << '\n';
    if (!dy.allFinite()) throw RunError("benchmark state produced non-finite derivatives");
  }
  std::printf("\nroofline, one thread: this machine's triad bandwidth %.1f GB/s, multiply-add peak of this build %.1f GFLOP/s\n"
              "(flops per body per evaluation: scripts/count_flops.py 'mbsflow::MultibodySystem::rhs*' -- mbsflow bench rhs ...)\n",
              roof.triad_gb_s, roof.peak_gflop_s);
  std::printf("%10s %10s %14s %14s %14s %12s %14s\n", "bodies", "ns/body", "bytes/body", "compiled B", "workspace B", "GB/s",
              "of triad");
  for (const Row& r : rows)
    std::printf("%10d %10.1f %14.0f %14.0f %14.0f %12.2f %13.0f%%\n", r.bodies, r.ns, r.bytes, r.compiled, r.workspace,
                r.bytes / r.ns, 100.0 * r.bytes / r.ns / roof.triad_gb_s);
  std::printf("written to %s\n", csv_path.c_str());
  const std::string rigid_csv = csv_path.size() > 4 && csv_path.ends_with(".csv")
                                    ? csv_path.substr(0, csv_path.size() - 4) + "_rigid.csv"
                                    : csv_path + "_rigid";
  rigid_models(a, rigid_csv);
  return 0;
}

}  // namespace mbsflow::cli
