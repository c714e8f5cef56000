// mbsflow bench load: how generating, loading and starting a model grow with its size.
// Each phase runs as its own mbsflow process (so that its peak memory is its own, read
// from the kernel): `generate` writes the model file, `run` reads it, checks it, sets up
// the run, takes one step and writes the results file. The table gives wall time and
// peak resident memory against N, and the exponent of a least-squares fit t ~ N^p.
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/line_fit.hpp"
#include "shared_files.hpp"

extern char** environ;

namespace mbsflow::cli {
namespace {

struct Measured {
  double seconds = 0.0;
  double peak_mb = 0.0;  // the process's peak resident set
};

// Runs this mbsflow executable with args, its output kept in log; RunError with the
// log's text if it fails.
Measured run_self(const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> all{"mbsflow"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : all) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  const auto start = BenchClock::now();
  pid_t pid = 0;
  const int failed = posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0) throw RunError("bench load: cannot start mbsflow " + args.front());
  int status = 0;
  rusage usage{};
  if (::wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw RunError("bench load: mbsflow " + args.front() + " failed: " + file_text(log));
  return {seconds_since(start), static_cast<double>(usage.ru_maxrss) / 1024.0};
}

struct LoadRow {
  std::string kind;
  long bodies = 0;
  Measured generate, start;
};

}  // namespace

int bench_load(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{1000, 10000, 100000, 1000000} : a.bodies;
  const std::vector<std::string> kinds = a.problems.empty() ? std::vector<std::string>{"chain", "grid"} : a.problems;
  if (!std::filesystem::is_directory(a.dir)) throw InputError("--dir: " + a.dir + " is not a folder");
  std::vector<LoadRow> rows;
  std::printf("load: generate, then read, check, set up and take one step (own processes; peak = the process's peak "
              "resident memory)\n");
  std::printf("%-6s %9s %11s %11s %13s %11s %11s\n", "model", "bodies", "generate s", "gen MB", "load+start s", "peak MB",
              "bytes/body");
  for (const std::string& kind : kinds) {
    if (kind != "chain" && kind != "grid") throw InputError("bench load: --problems takes chain and grid (got '" + kind + "')");
    for (int n : sizes) {
      const std::string stem = (std::filesystem::path(a.dir) / ("mbsflow_bench_load_" + kind)).string();
      std::vector<std::string> gen{"generate", kind, "-o", stem + ".json"};
      long bodies = n;
      if (kind == "grid") {  // the nearest square plate
        const long side = std::max(1L, std::lround(std::sqrt(static_cast<double>(n))));
        bodies = side * side;
        gen.insert(gen.end(), {"--rows", std::to_string(side), "--cols", std::to_string(side)});
      } else {
        gen.insert(gen.end(), {"--bodies", std::to_string(n)});
      }
      LoadRow r{kind, bodies, run_self(gen, stem + ".log"), {}};
      r.start = run_self({"run", stem + ".json", "--t-end", "1e-9", "-q", "-o", stem + ".h5"}, stem + ".log");
      std::filesystem::remove(stem + ".log");
      std::filesystem::remove(stem + ".json");
      std::filesystem::remove(stem + ".h5");
      std::filesystem::remove(stem + ".xdmf");
      std::printf("%-6s %9ld %11.3f %11.1f %13.3f %11.1f %11.0f\n", kind.c_str(), r.bodies, r.generate.seconds,
                  r.generate.peak_mb, r.start.seconds, r.start.peak_mb, r.start.peak_mb * 1048576.0 / static_cast<double>(r.bodies));
      std::fflush(stdout);
      rows.push_back(r);
    }
  }
  auto [csv_path, csv] = open_csv(a);
  csv << "model,bodies,generate_s,generate_peak_MB,load_start_s,load_start_peak_MB\n";
  for (const LoadRow& r : rows)
    csv << r.kind << ',' << r.bodies << ',' << r.generate.seconds << ',' << r.generate.peak_mb << ',' << r.start.seconds << ','
        << r.start.peak_mb << '\n';
  // Exponents over the sizes from 10 000 bodies on, where a process's fixed cost no
  // longer dominates (all sizes where fewer than two are that large).
  for (const std::string& kind : kinds) {
    std::vector<double> x, t, m;
    for (bool large_only : {true, false}) {
      x.clear(), t.clear(), m.clear();
      for (const LoadRow& r : rows)
        if (r.kind == kind && (!large_only || r.bodies >= 10000)) {
          x.push_back(static_cast<double>(r.bodies));
          t.push_back(r.start.seconds);
          m.push_back(r.start.peak_mb);
        }
      if (x.size() >= 2) break;
    }
    if (x.size() >= 2)
      std::printf("%s: load+start time ~ N^%.2f, peak memory ~ N^%.2f (fitted from %.0f to %.0f bodies)\n", kind.c_str(),
                  log_log_slope(x, t), log_log_slope(x, m), x.front(), x.back());
  }
  std::printf("written to %s\n", csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
