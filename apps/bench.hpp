#pragma once
// The benchmarks of `mbsflow bench`: each prints a table and writes a CSV file.
#include <chrono>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow::cli {

struct BenchArgs {
  std::string what;
  std::vector<int> bodies;  // default per benchmark
  double seconds = 1.0;     // rhs: time per measurement
  int steps = 1000;         // output: steps per run
  int repeats = 3;          // output, parallel, cluster, iftomm: runs per case, the fastest counts
  std::string dir = ".";    // output: where the results files go
  std::string csv;          // default: bench_WHAT.csv
  int threads = 0;          // parallel: up to this many threads (default: all cores)
  int processes = -1;       // parallel: 2 .. this many worker processes (default: up to 4, at most the cores; 0 or 1: none)
  std::vector<std::string> executors;  // parallel: flow, barrier (default both)
  std::vector<std::string> problems;  // ode: default hnw, b1, heat1000, heat100000, heat1000000
  std::vector<double> tolerances;     // ode: default 1e-4, 1e-6, 1e-8, 1e-10
  std::string tableau;                // iterations: default radau3
  std::vector<double> frequencies;    // stiff: the chain's bushing frequencies (default 1e3, 1e4, 1e5 rad/s)
  double t_end = 0;                   // stiff: model time (default per model)
  // Tolerance of the reference run; 0: stiff 1e-6 (1e-7 is slow on the 2000-body chain at
  // 1e5: notes/methods-measurements.md), ivp 1e-12.
  double reference_tol = 0;
  double target_error = 1e-3;         // stiff: the error at which methods are compared
  std::vector<std::string> methods;   // stiff, ivp: which methods run (default all)
  double atol_ratio = 0;               // ivp: atol = this times rtol for every component; 0: rtol times its scale
};

// The CSV file of a benchmark: --csv, or bench_WHAT.csv; InputError if it cannot be written.
struct BenchCsv {
  std::string path;
  std::ofstream out;
};
inline BenchCsv open_csv(const BenchArgs& a) {
  BenchCsv c{a.csv.empty() ? "bench_" + a.what + ".csv" : a.csv, {}};
  c.out.open(c.path);
  if (!c.out) throw InputError("--csv: cannot write " + c.path);
  return c;
}

int bench_rhs(const BenchArgs& a);
int bench_iftomm(const BenchArgs& a);
int bench_output(const BenchArgs& a);
int bench_parallel(const BenchArgs& a);
int bench_cluster(const BenchArgs& a);
int bench_latency(const BenchArgs& a);
int bench_ode(const BenchArgs& a);
int bench_iterations(const BenchArgs& a);
int bench_stiff(const BenchArgs& a);
int bench_ivp(const BenchArgs& a);
int bench_load(const BenchArgs& a);
int bench_beams(const BenchArgs& a);

// Where the example models are: --dir, or examples/models (run from the source tree).
inline std::string examples_dir(const BenchArgs& a) { return a.dir == "." ? "examples/models" : a.dir; }

// Keeps every snapshot's time and state, or only the body positions (the state's first
// 3 entries per body).
struct KeptStates : ResultSink {
  bool positions_only = false;
  std::vector<double> t;
  std::vector<Eigen::VectorXd> y;
  void begin(const MultibodySystem& s) override { rows_ = positions_only ? 3 * s.layout().bodies : s.dimension(); }
  void write(Snapshot&& s) override {
    t.push_back(s.t);
    y.emplace_back(s.state.head(rows_));
  }
  void end() override {}

 private:
  Eigen::Index rows_ = 0;
};

using BenchClock = std::chrono::steady_clock;
inline double seconds_since(BenchClock::time_point start) {
  return std::chrono::duration<double>(BenchClock::now() - start).count();
}

// Repeats f until `seconds` have passed; returns seconds per call.
template <class F>
inline double time_per_call(double seconds, F f) {
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
inline Eigen::VectorXd perturbed_state(const MultibodySystem& sys) {
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


}  // namespace mbsflow::cli
