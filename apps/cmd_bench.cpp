// mbsflow bench WHAT: benchmarks that print a table and write CSV.
#include <memory>

#include "bench.hpp"
#include "commands.hpp"

namespace mbsflow::cli {

Action add_bench(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* sub = app.add_subcommand("bench", "Benchmarks that print a table and write CSV");
  sub->add_option("what", a->what,
                  "rhs: cost of one right-hand-side evaluation per body; "
                  "output: cost of writing results (6500-body chain, none / every 10 steps / every step); "
                  "parallel: scaling of partitioned runs over 1, 2, 4, ... threads (flow graph vs barrier) and 2..4 "
                  "processes, against the efficiency mbsflow plan predicts; "
                  "cluster: 2 threads vs 2 processes over tcp and ipc, exchange cost, predicted speedup on a cluster; "
                  "latency: tight vs loose coupling on 2 processes as the network gets slower; "
                  "ode: work-precision of the block and tirk methods against CVODE and Boost.Odeint on the standard test problems; "
                  "iterations: iteration error after 1, 2, ... iterations of the tirk schemes (the claimed convergence); "
                  "iftomm: the IFToMM examples against their reduced equations; "
                  "stiff: work-precision on stiff multibody models (chain at several bushing frequencies, train, A05) "
                  "against RK4 at its stable step, DOPRI5 and CVODE with KLU; "
                  "ivp: work-precision (correct digits at the end vs CPU time, rtol 1e-3..1e-10) of the implicit methods against "
                  "CVODE on Van der Pol (mu 1e3, 1e6), Robertson and the standard test problems; "
                  "load: time and memory to read, check, set up and start a large chain or grid (docs/parallel.md); "
                  "beams: cost per beam element against a bushing, a cantilever of --bodies elements through RK4 and tirk, and "
                  "the work-precision of the flexible boom's spin-up (docs/beams.md)")
      ->required()
      ->check(CLI::IsMember({"rhs", "output", "parallel", "cluster", "latency", "ode", "iterations", "iftomm", "stiff", "ivp", "load", "beams"}));
  sub->add_option("--problems", a->problems,
                  "ode, iterations: hnw, b1, heatN (default ode: hnw,b1,heat1000,heat100000,heat1000000; iterations: hnw,b1,heat200); "
                  "ivp: also vdpMU, robertson, hires, orego, e5, pollu (default vdp1e3,vdp1e6,robertson,hires,orego,e5,pollu,hnw,b1,heat1000); "
                  "stiff: chain, train, a05 (default all); load: chain, grid (default both)")
      ->delimiter(',');
  sub->add_option("--tableau", a->tableau, "iterations: the tirk tableau (default radau3)");
  sub->add_option("--tolerances", a->tolerances, "ode: tolerances (default 1e-4,1e-6,1e-8,1e-10); stiff: rtol = atol (default 1e-1,1e-2,1e-3,1e-4); beams: of the spin-up (default 1e-3,...,1e-7); "
                  "ivp: rtol, atol = rtol times the problem's absolute scale (default 1e-3,1e-4,...,1e-10)")
      ->delimiter(',');
  sub->add_option("--frequencies", a->frequencies, "stiff: the chain's bushing frequencies in rad/s (default 1e3,1e4,1e5)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  sub->add_option("--t-end", a->t_end, "stiff: model time in s (default: chain 0.2, train 1, A05 its file's 10); beams: of the cantilever (default 5e-5: RK4 takes some 16 000 steps of 3e-9 s on 10 000 elements, the torsion of 1 mm elements)")->check(CLI::PositiveNumber);
  sub->add_option("--atol-ratio", a->atol_ratio, "ivp: atol = R rtol for every component (1: one scalar tolerance, atol = rtol; 1e-4: four "
                  "decades below), instead of rtol times each component's absolute scale (Robertson: 1e-4, 1e-10, 1e-2)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--reference-tol", a->reference_tol, "stiff: tolerance of the tirk reference run (default 1e-6); ivp: of the colloc "
                  "reference run where a problem has neither exact solution nor published value (default 1e-12)")->check(CLI::PositiveNumber);
  sub->add_option("--target-error", a->target_error, "stiff: the position error (m) at which the summary compares methods (default 1e-3); an adaptive method none of whose runs reaches it on one thread runs again at tolerances ten times tighter than the tightest of --tolerances, down to 1e-9, until one does")
      ->check(CLI::PositiveNumber);
  sub->add_option("--methods", a->methods,
                  "stiff: the methods compared with the reference: rk4, dopri5, tirk-newton, tirk-newton-triangular, colloc, "
                  "cvode-klu (default all); ivp: colloc, colloc-s2, tirk-newton, tirk-newton-triangular, cvode-bdf (default all)")
      ->delimiter(',')
      ->check(CLI::IsMember({"rk4", "dopri5", "tirk-newton", "tirk-newton-triangular", "colloc", "colloc-s2", "cvode-klu", "cvode-bdf"}));
  sub->add_option("--bodies", a->bodies, "Chain sizes (rhs: 2000,6500,100000; output: 6500; parallel, cluster: 2000,4000,6500; stiff: 2000; load: 1000,10000,100000,1000000, a grid the nearest square; beams: elements, 10000)")
      ->delimiter(',');
  sub->add_option("--threads", a->threads, "parallel: 1, 2, 4, ... up to this many threads (default: all cores); ivp: the thread count "
                  "of the parallel runs beside the sequential ones, on problems of 100 or more equations (default 2)")->check(CLI::PositiveNumber);
  sub->add_option("--processes", a->processes, "parallel: also 2 .. this many worker processes of one thread over "
                  "loopback tcp (default: up to 4, at most the cores; 0: none)")->check(CLI::NonNegativeNumber);
  sub->add_option("--executors", a->executors, "parallel: the thread runs' executors, flow and barrier (default both)")
      ->delimiter(',')
      ->check(CLI::IsMember({"flow", "barrier"}));
  sub->add_option("--seconds", a->seconds, "rhs, beams: time per measurement")->check(CLI::PositiveNumber);
  sub->add_option("--steps", a->steps, "output: steps per run")->check(CLI::PositiveNumber);
  sub->add_option("--repeats", a->repeats, "output, parallel, cluster, iftomm: runs per case; the fastest counts")->check(CLI::PositiveNumber);
  sub->add_option("--dir", a->dir, "output, load: folder for the results and model files (the disk being measured); iftomm, stiff, beams: the example models (default examples/models)");
  sub->add_option("--csv", a->csv, "CSV file to write (default bench_WHAT.csv)");
  return [a] {
    if (a->what == "rhs") return bench_rhs(*a);
    if (a->what == "output") return bench_output(*a);
    if (a->what == "cluster") return bench_cluster(*a);
    if (a->what == "latency") return bench_latency(*a);
    if (a->what == "ode") return bench_ode(*a);
    if (a->what == "iterations") return bench_iterations(*a);
    if (a->what == "iftomm") return bench_iftomm(*a);
    if (a->what == "stiff") return bench_stiff(*a);
    if (a->what == "ivp") return bench_ivp(*a);
    if (a->what == "load") return bench_load(*a);
    if (a->what == "beams") return bench_beams(*a);
    return bench_parallel(*a);
  };
}

}  // namespace mbsflow::cli
