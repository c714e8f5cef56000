// mbsflow bench latency: what a slow network costs tight and loose coupling. A train of
// about 6500 bodies (weakly coupled wagons: the case loose coupling is for) on 2 worker
// processes, every boundary message held back 0, 1, 5, 20 and 50 ms (--exchange-delay's
// channel): throughput (simulated seconds per wall second) of tight coupling (4 exchanges
// per RK4 step) and of loose coupling (1 per macro step: of one RK4 step, without and with
// a lag of one macro step, and of the default 16 steps with its overlap, fixed and with
// error control), each against its own throughput without delay, and each run's largest
// position error against the tight run's end state.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>

#include "bench.hpp"
#include "local_workers.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"

namespace mbsflow::cli {

int bench_latency(const BenchArgs& a) {
  const int bodies = a.bodies.empty() ? 6500 : a.bodies.front();
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,delay_ms,coupling,max_lag,steps_per_macro_step,coupling_tol,wall_s,simulated_per_wall,relative,error_m\n";
  TrainParams p;
  p.wagons = std::max(1, bodies / 7);
  const Model m = make_train(p);
  const std::string json = model_to_json(m);
  RunOptions o = options_from_model(m);
  const int steps = 32;  // RK4 steps of the stable step: two default macro steps
  o.t_end = o.t_start + steps * o.step;
  o.output_every = steps;
  const Decomposition d = decompose(m, 2);
  std::printf("train of %zu bodies, 2 worker processes (tcp loopback), %d RK4 steps of %.4g s, fastest of %d runs\n",
              m.bodies.size(), steps, o.step, a.repeats);
  std::printf("%9s %-34s %12s %14s %10s %12s\n", "delay ms", "coupling", "wall s", "sim s / wall s", "vs no delay",
              "error m");
  struct Case {
    const char* name;
    bool loose;
    int lag, steps_per_macro_step;
    double coupling_tol;
  };
  const Case cases[] = {{"tight", false, 0, 0, 0.0},
                        {"loose, H = step", true, 0, 1, 0.0},
                        {"loose, H = step, lag 1", true, 1, 1, 0.0},
                        {"loose, H = 16 steps, overlap", true, 0, default_macro_steps, 0.0},
                        {"loose, defaults (+ error control)", true, 0, default_macro_steps, default_coupling_tol}};
  constexpr int n_cases = sizeof cases / sizeof cases[0];
  double base[n_cases] = {};
  Eigen::VectorXd tight;  // the end state without delay
  MultibodySystem whole(m);
  for (const double delay_ms : {0.0, 1.0, 5.0, 20.0, 50.0}) {
    for (int c = 0; c < n_cases; ++c) {
      LooseOptions lo;
      lo.macro_step = cases[c].steps_per_macro_step * o.step;
      lo.extrapolation = 1;
      lo.max_lag = cases[c].lag;
      lo.coupling_tol = cases[c].coupling_tol;
      double best = std::numeric_limits<double>::infinity(), error = 0.0;
      for (int r = 0; r < a.repeats; ++r) {
        LocalWorkers workers(2, "tcp", 1);
        const RunSummary s = run_cluster(m, json, d, workers.cluster(), o, nullptr, nullptr,
                                         {cases[c].loose ? &lo : nullptr, delay_ms / 1000.0});
        best = std::min(best, s.wall_seconds);
        if (tight.size() == 0) tight = s.final_state;
        error = std::max(error, largest_position_gap(whole.layout(), s.final_state, tight));
      }
      const double rate = (o.t_end - o.t_start) / best;
      if (delay_ms == 0.0) base[c] = rate;
      std::printf("%9g %-34s %12.3f %14.4f %10.2f %12.3g\n", delay_ms, cases[c].name, best, rate, rate / base[c], error);
      csv << m.bodies.size() << ',' << delay_ms << ',' << (cases[c].loose ? "loose" : "tight") << ',' << cases[c].lag << ','
          << cases[c].steps_per_macro_step << ',' << cases[c].coupling_tol << ',' << best << ',' << rate << ',' << rate / base[c] << ',' << error << '\n';
    }
  }
  std::printf("written to %s\n", csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
