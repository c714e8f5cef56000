// mbsflow bench parallel: the seed's scaling table on this machine. For chain models of
// several sizes and 1..cores threads: time per simulated second, speedup over the
// single-thread sequential run, efficiency, and the share of time threads spent waiting
// for neighbours (flow graph) or at the stage barrier (the seed's scheme).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <thread>

#include "bench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"

namespace mbsflow::cli {

int bench_parallel(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{2000, 4000, 6500} : a.bodies;
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int max_threads = a.threads > 0 ? a.threads : cores;
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,executor,threads,partitions,steps,wall_s,s_per_simulated_s,speedup,efficiency,wait_fraction\n";
  std::printf("partitioned RK4 on generate chain models, %d cores here, fastest of %d runs\n", cores, a.repeats);
  std::printf("%8s %-10s %7s %10s %12s %8s %10s %7s\n", "bodies", "executor", "threads", "steps", "s per sim s", "speedup",
              "efficiency", "wait");
  for (const int n : sizes) {
    ChainParams p;
    p.bodies = n;
    const Model m = make_chain(p);
    RunOptions o = options_from_model(m);
    // About half a second of single-thread work per run.
    const long steps = std::max<long>(10, std::lround(1.2e6 / n));
    o.t_end = o.t_start + static_cast<double>(steps) * o.step;
    const double simulated = o.t_end - o.t_start;
    auto fastest = [&](auto run) {
      double best = std::numeric_limits<double>::infinity(), wait = 0.0;
      for (int r = 0; r < a.repeats; ++r) {
        ParallelStats stats;
        const double wall = run(stats);
        if (wall < best) {
          best = wall;
          wait = stats.wait_fraction;
        }
      }
      return std::pair{best, wait};
    };
    const double serial = fastest([&](ParallelStats&) {
      MultibodySystem sys(m);
      return run_simulation(sys, o, nullptr).wall_seconds;
    }).first;
    auto row = [&](const char* executor, int threads, int parts, double wall, double wait) {
      const double speedup = serial / wall;
      std::printf("%8d %-10s %7d %10ld %12.3f %8.2f %10.2f %6.1f%%\n", n, executor, threads, steps, wall / simulated,
                  speedup, speedup / threads, 100.0 * wait);
      csv << n << ',' << executor << ',' << threads << ',' << parts << ',' << steps << ',' << wall << ',' << wall / simulated
          << ',' << speedup << ',' << speedup / threads << ',' << wait << '\n';
    };
    row("sequential", 1, 1, serial, 0.0);
    for (int threads = 1; threads <= max_threads; ++threads) {
      const Decomposition d = decompose(m, threads);
      for (Executor ex : {Executor::flow_graph, Executor::barrier}) {
        const auto [wall, wait] = fastest([&](ParallelStats& stats) {
          return run_partitioned(m, d, o, {threads, ex}, nullptr, &stats).wall_seconds;
        });
        row(ex == Executor::flow_graph ? "flow" : "barrier", threads, threads, wall, wait);
      }
    }
  }
  std::printf("written to %s (plot: /usr/bin/python3 scripts/plot_bench.py %s)\n", csv_path.c_str(), csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
