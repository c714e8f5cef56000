#pragma once
// The benchmarks of `mbsflow bench`: each prints a table and writes a CSV file.
#include <chrono>
#include <fstream>
#include <string>
#include <vector>

#include "mbsflow/error.hpp"
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
  // 1e5: docs/methods.md), ivp 1e-12.
  double reference_tol = 0;
  double target_error = 1e-3;         // stiff: the error at which methods are compared
  std::vector<std::string> methods;   // stiff, ivp: which methods run (default all)
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

}  // namespace mbsflow::cli
