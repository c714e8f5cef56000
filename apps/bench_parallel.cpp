// mbsflow bench parallel: the seed's scaling table on this machine. For chain models of
// several sizes: time per simulated second on 1, 2, 4, ... threads (flow graph, and the
// seed's stage barrier) and on 2..P worker processes over loopback tcp (ZeroMQ), the
// speedup over the single-thread sequential run, the efficiency, the share of time
// threads spent waiting, and the efficiency `mbsflow plan` predicts for the same cut:
// the slowest submodel's estimated work at the measured cost per unit, plus for processes
// the Hockney time of its boundary messages (alpha and beta fitted on loopback tcp here).
// The prediction leaves out what threads share (memory bandwidth, caches) and the
// scheduling: the gap between the two columns is that cost.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <thread>

#include "bench.hpp"
#include "exchange_cost.hpp"
#include "local_workers.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "run_prediction.hpp"

namespace mbsflow::cli {
namespace {

// 1, 2, 4, ... below `most`, then `most` itself.
std::vector<int> doubling_up_to(int most) {
  std::vector<int> counts;
  for (int n = 1; n < most; n *= 2) counts.push_back(n);
  counts.push_back(most);
  return counts;
}

}  // namespace

int bench_parallel(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{2000, 4000, 6500} : a.bodies;
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int max_threads = a.threads > 0 ? a.threads : cores;
  const int max_processes = a.processes >= 0 ? a.processes : std::min(4, cores);
  const std::vector<std::string> executors = a.executors.empty() ? std::vector<std::string>{"flow", "barrier"} : a.executors;
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,executor,threads,partitions,steps,wall_s,s_per_simulated_s,speedup,efficiency,wait_fraction,"
         "predicted_speedup,predicted_efficiency\n";
  Hockney tcp;
  if (max_processes >= 2) {
    tcp = fit_loopback_tcp();
    std::printf("loopback tcp between two processes: alpha %.1f us, beta %.0f MB/s (Hockney fit, the processes' prediction)\n",
                1e6 * tcp.alpha, tcp.beta / 1e6);
  }
  std::printf("partitioned RK4 on generate chain models, %d cores here, fastest of %d runs (set-up excluded)\n", cores,
              a.repeats);
  std::printf("%8s %-10s %7s %10s %12s %8s %10s %9s %7s\n", "bodies", "executor", "workers", "steps", "s per sim s", "speedup",
              "efficiency", "predicted", "wait");
  for (const int n : sizes) {
    ChainParams p;
    p.bodies = n;
    const Model m = make_chain(p);
    RunOptions o = options_from_model(m);
    // About half a second of single-thread work per run.
    const long steps = std::max<long>(10, std::lround(1.2e6 / n));
    o.t_end = o.t_start + static_cast<double>(steps) * o.step;
    o.output_every = static_cast<int>(steps);  // results only at the end (process runs send them to the coordinator)
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
    long evaluations = 0;
    const double serial = fastest([&](ParallelStats&) {
      MultibodySystem sys(m);
      const RunSummary r = run_simulation(sys, o, nullptr);
      evaluations = r.evaluations;
      return r.wall_seconds;
    }).first;
    // The prediction's unit: what one unit of estimated work took in the sequential run.
    const double seconds_per_stage = serial / static_cast<double>(std::max(1L, evaluations));
    const double seconds_per_cost = seconds_per_stage / decompose(m, 1).estimated_time();
    auto row = [&](const char* executor, int workers, int parts, double wall, double wait, double predicted_stage_s) {
      const double speedup = serial / wall, predicted = seconds_per_stage / predicted_stage_s;
      std::printf("%8d %-10s %7d %10ld %12.3f %8.2f %10.2f %9.2f %6.1f%%\n", n, executor, workers, steps, wall / simulated,
                  speedup, speedup / workers, predicted / workers, 100.0 * wait);
      csv << n << ',' << executor << ',' << workers << ',' << parts << ',' << steps << ',' << wall << ',' << wall / simulated
          << ',' << speedup << ',' << speedup / workers << ',' << wait << ',' << predicted << ',' << predicted / workers << '\n';
      std::fflush(stdout);
      csv.flush();
    };
    row("sequential", 1, 1, serial, 0.0, seconds_per_stage);
    for (const int threads : doubling_up_to(max_threads)) {
      const Decomposition d = decompose(m, threads);
      const double predicted = predict_stage(d, 1, threads, seconds_per_cost, tcp).stage_s();
      for (const std::string& name : executors) {
        const Executor ex = name == "barrier" ? Executor::barrier : Executor::flow_graph;
        const auto [wall, wait] = fastest([&](ParallelStats& stats) {
          return run_partitioned(m, d, o, {threads, ex}, nullptr, &stats).wall_seconds;
        });
        row(name.c_str(), threads, threads, wall, wait, predicted);
      }
    }
    if (max_processes < 2) continue;
    const std::string json = model_to_json(m);
    for (int procs = 2; procs <= max_processes; ++procs) {
      // Worker processes of one thread each, one submodel each; this process coordinates.
      const Decomposition d = decompose(m, procs);
      const double predicted = predict_stage(d, procs, 1, seconds_per_cost, tcp).stage_s();
      const double wall = fastest([&](ParallelStats&) {
        LocalWorkers workers(procs, "tcp", 1);
        return run_cluster(m, json, d, workers.cluster(), o, nullptr).wall_seconds;
      }).first;
      row("processes", procs, procs, wall, 0.0, predicted);
    }
  }
  std::printf("predicted: the efficiency mbsflow plan predicts for the cut (slowest submodel, and for processes the Hockney "
              "time of its messages); threads' shared memory bandwidth and scheduling are not in it\n");
  std::printf("written to %s (plot: /usr/bin/python3 scripts/plot_bench.py %s)\n", csv_path.c_str(), csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
