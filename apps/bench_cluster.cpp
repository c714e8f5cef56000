// mbsflow bench cluster: what running across processes costs on this host, and what it
// would give on a cluster. For chain models: one thread, two threads in one process, and
// two worker processes over tcp (loopback) and ipc; the exchange time per message size
// with its Hockney fit t(m) = alpha + m/beta; and from the fit and the measured compute,
// the predicted speedup on P hosts joined by Gigabit Ethernet, next to the seed's table.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>

#include "bench.hpp"
#include "local_workers.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "exchange_cost.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "run_prediction.hpp"

namespace mbsflow::cli {
namespace {

// The seed's measurements (7 nodes x 2 quad-core Xeon 2.5 GHz, Gigabit Ethernet).
struct SeedRow {
  int bodies;
  double one, p16, p24, p32;  // seconds
};
constexpr SeedRow seed[] = {{2000, 200, 42, 34, 30}, {4000, 410, 93, 57, 45}, {6500, 800, 203, 99, 70}};

}  // namespace

int bench_cluster(const BenchArgs& a) {
  const std::vector<int> sizes = a.bodies.empty() ? std::vector<int>{2000, 4000, 6500} : a.bodies;
  auto [csv_path, csv] = open_csv(a);
  csv << "table,bodies,case,processes,threads,steps,wall_s,s_per_step,speedup,efficiency,exchange_s_per_stage,bytes,seconds\n";

  // 1. The exchange: one-way time per message size, tcp and ipc.
  const std::vector<std::size_t> bytes = {0, 128, 1024, 8192, 65536, 262144};
  std::map<std::string, Hockney> fit;
  std::printf("one-way message time between two processes' sockets on this host (median of 2000 round trips)\n");
  std::printf("%10s %12s %12s\n", "bytes", "tcp us", "ipc us");
  const auto tcp = measure_exchange("tcp", bytes, 2000), ipc = measure_exchange("ipc", bytes, 2000);
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::printf("%10zu %12.1f %12.1f\n", bytes[i], 1e6 * tcp[i].seconds, 1e6 * ipc[i].seconds);
    csv << "exchange,,tcp,,,,,,,,," << bytes[i] << ',' << tcp[i].seconds << '\n';
    csv << "exchange,,ipc,,,,,,,,," << bytes[i] << ',' << ipc[i].seconds << '\n';
  }
  fit["tcp"] = fit_hockney(tcp);
  fit["ipc"] = fit_hockney(ipc);
  std::printf("Hockney fit t(m) = alpha + m/beta: tcp alpha %.1f us, beta %.0f MB/s; ipc alpha %.1f us, beta %.0f MB/s\n\n",
              1e6 * fit["tcp"].alpha, fit["tcp"].beta / 1e6, 1e6 * fit["ipc"].alpha, fit["ipc"].beta / 1e6);

  // 2. The runs: one thread, two threads, two processes over tcp and ipc.
  std::printf("RK4 on generate chain models, fastest of %d runs (set-up excluded)\n", a.repeats);
  std::printf("%8s %-16s %8s %12s %8s %10s %16s\n", "bodies", "case", "steps", "us per step", "speedup", "efficiency",
              "exchange us/stage");
  std::map<int, double> per_step_one;  // single-thread time per step, by size
  for (const int n : sizes) {
    ChainParams p;
    p.bodies = n;
    const Model m = make_chain(p);
    const std::string json = model_to_json(m);
    RunOptions o = options_from_model(m);
    const long steps = std::max<long>(50, std::lround(2.4e6 / n));  // about a second of one-thread work
    o.t_end = o.t_start + static_cast<double>(steps) * o.step;
    o.output_every = static_cast<int>(steps);  // results only at the end: the exchange is measured, not the output
    auto fastest = [&](auto run) {
      double best = std::numeric_limits<double>::infinity();
      for (int r = 0; r < a.repeats; ++r) best = std::min(best, run());
      return best / static_cast<double>(steps);
    };
    const double one = fastest([&] {
      MultibodySystem sys(m);
      return run_simulation(sys, o, nullptr).wall_seconds;
    });
    per_step_one[n] = one;
    const Decomposition d = decompose(m, 2);
    const double threads = fastest([&] { return run_partitioned(m, d, o, {2, Executor::flow_graph}, nullptr).wall_seconds; });
    auto row = [&](const std::string& what, int procs, int thr, double t, double exchange) {
      const double speedup = one / t;
      const int workers = procs * thr;
      std::printf("%8d %-16s %8ld %12.1f %8.2f %10.2f %16s\n", n, what.c_str(), steps, 1e6 * t, speedup, speedup / workers,
                  exchange > 0 ? std::to_string(static_cast<int>(std::lround(1e6 * exchange))).c_str() : "");
      csv << "run," << n << ',' << what << ',' << procs << ',' << thr << ',' << steps << ',' << t * static_cast<double>(steps)
          << ',' << t << ',' << speedup << ',' << speedup / workers << ',' << exchange << ",,\n";
    };
    row("1 thread", 1, 1, one, 0.0);
    row("2 threads", 1, 2, threads, 0.0);
    for (const std::string transport : {"tcp", "ipc"}) {
      const double procs = fastest([&] {
        LocalWorkers workers(2, transport, 1);
        return run_cluster(m, json, d, workers.cluster(), o, nullptr).wall_seconds;
      });
      // What the processes lose against the threads, per stage: the exchange's cost.
      row("2 processes " + transport, 2, 1, procs, std::max(0.0, (procs - threads) / 4.0));
      std::printf("%8s %-16s   2-process speedup / 2-thread speedup = %.2f\n", "", "", threads / procs);
    }
  }

  // 3. The prediction for P hosts on Gigabit Ethernet: compute split P ways, plus per
  // stage the exchange with two neighbours (a chain's band cut: one boundary body each
  // way). Without overlap a stage costs compute + exchange; with the workers' overlap
  // (the inner half of a stage runs while the boundary values travel) the larger of the
  // two, when a core is free for the messages (not so on this 2-core host).
  const Hockney local = fit["tcp"];
  const Hockney gbe = gigabit_ethernet(local);
  const double message = boundary_message_bytes(1);  // from each of two neighbours: one body and a header
  std::printf("\npredicted speedup on P hosts over Gigabit Ethernet (assumed: alpha = measured tcp alpha + %.0f us = %.1f us,"
              " beta = %.0f MB/s),\nfrom this host's one-thread time per step; the published cluster's measured speedups (16/24/32 "
              "processes on 7 nodes) in brackets\n",
              1e6 * gbe_extra_latency_s, 1e6 * gbe.alpha, gbe.beta / 1e6);
  const int hosts[] = {2, 4, 8, 16, 24, 32};
  for (const bool overlap : {false, true}) {
    std::printf("%s\n%8s %10s", overlap ? "exchange overlapped with the inner half of each stage:" : "exchange after compute:",
                "bodies", "us/step");
    for (int h : hosts) std::printf(" %9s", ("P=" + std::to_string(h)).c_str());
    std::printf("\n");
    for (const SeedRow& s : seed) {
      // The seed's sizes as chains; the compute per step scales with the bodies.
      const auto near = per_step_one.lower_bound(s.bodies);
      const auto& [measured_n, measured_t] = near == per_step_one.end() ? *per_step_one.rbegin() : *near;
      const double t1 = measured_t * s.bodies / measured_n;
      std::printf("%8d %10.1f", s.bodies, 1e6 * t1);
      for (int h : hosts) {
        const double stage = t1 / (4.0 * h), exchange = 2.0 * gbe.time(message);
        const double tp = 4.0 * (overlap ? std::max(stage, exchange) : stage + exchange);
        const double speedup = t1 / tp;
        const double seen = h == 16 ? s.one / s.p16 : h == 24 ? s.one / s.p24 : h == 32 ? s.one / s.p32 : 0.0;
        char cell[32];
        if (seen > 0)
          std::snprintf(cell, sizeof cell, "%.1f[%.1f]", speedup, seen);
        else
          std::snprintf(cell, sizeof cell, "%.1f", speedup);
        std::printf(" %9s", cell);
        csv << (overlap ? "prediction_overlap," : "prediction,") << s.bodies << ",gbe," << h << ",1,,," << tp << ','
            << speedup << ',' << speedup / h << ',' << exchange << ',' << message << ',' << seen << '\n';
      }
      std::printf("\n");
    }
  }
  std::printf("written to %s\n", csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
