// mbsflow bench stiff end to end on a small chain: every method runs, CVODE included,
// each row has a finite error against the reference, and the work-precision plot draws it.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"

using namespace mbsflow::test;

namespace {

// bench stiff on a 6-body chain at Omega = 1e4 over 0.02 s, one thread, in a scratch folder
// of its own: the output, and the CSV's header and rows cell by cell.
struct StiffBench {
  std::string dir;
  Result result;
  std::string header;
  std::vector<std::vector<std::string>> rows;
};

StiffBench bench_stiff_chain(const std::string& name, const std::string& options) {
  StiffBench b;
  b.dir = scratch(name.c_str()).string();
  b.result = run("bench stiff --problems chain --bodies 6 --frequencies 1e4 --t-end 0.02 --threads 1 --csv stiff.csv " + options,
                 b.dir, true);
  if (b.result.code != 0) return b;
  std::istringstream csv(read_text(fs::path(b.dir) / "stiff.csv"));
  std::getline(csv, b.header);
  for (std::string line; std::getline(csv, line);) b.rows.push_back(csv_cells(line));
  return b;
}

}  // namespace

TEST_CASE("cli bench stiff: a stiff chain against RK4, DOPRI5 and CVODE, CSV and plot", "[cli][bench]") {
  const StiffBench b = bench_stiff_chain("bench_stiff", "--tolerances 1e-3");
  const std::string& dir = b.dir;
  INFO(b.result.err << b.result.out);
  REQUIRE(b.result.code == 0);
  CHECK(b.result.out.find("fastest run on 1 thread with error <= 1e-03 m") != std::string::npos);
  CHECK(b.header == "model,method,threads,tol,steps,evaluations,jacobians,factorizations,wall_s,error_m,note");
  std::string methods;
  for (const std::vector<std::string>& cells : b.rows) {
    REQUIRE(cells.size() >= 10);
    methods += cells[1] + " ";
    const double error = std::stod(cells[9]);
    INFO(cells[1] << " " << cells[3]);
    CHECK(error < 1e-2);  // every method at 1e-3 lands well within a centimetre on this chain
    if (cells[1].rfind("tirk", 0) == 0 || cells[1] == "colloc") CHECK(std::stol(cells[6]) >= 1);  // Jacobians counted
  }
  CHECK(b.rows.size() == 7);
  CHECK(methods == "reference rk4 dopri5 tirk-newton tirk-newton-triangular colloc cvode-klu ");
  const std::string python = MBSFLOW_PYTHON;
  const int plot = std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot_work_precision.py' '" + dir +
                                "/stiff.csv' -o '" + dir + "/stiff.png' >/dev/null")
                                   .c_str());
  CHECK(plot == 0);
  CHECK(fs::file_size(fs::path(dir) / "stiff.png") > 10000);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench stiff: a method that misses the target error runs again at tighter tolerances", "[cli][bench]") {
  // At tol 1e-1 no method lands within 1e-5 m on this chain; each is run again at 1e-2,
  // 1e-3, ... (one thread) until one run does, and stops there.
  const StiffBench b = bench_stiff_chain("bench_stiff_tighten",
                                         "--tolerances 1e-1 --target-error 1e-5 --methods dopri5 tirk-newton cvode-klu");
  const Result& r = b.result;
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  std::map<std::string, std::vector<std::pair<double, double>>> runs;  // method -> (tol, error) in order
  for (const std::vector<std::string>& cells : b.rows) {
    REQUIRE(cells.size() >= 10);
    if (cells[1] != "reference") runs[cells[1]].emplace_back(std::stod(cells[3]), std::stod(cells[9]));
  }
  REQUIRE(runs.size() == 3);
  for (const auto& [method, list] : runs) {
    INFO(method);
    REQUIRE(list.size() >= 2);
    for (std::size_t k = 0; k < list.size(); ++k) {
      CHECK(list[k].first == Approx(0.1 * std::pow(0.1, static_cast<double>(k))));  // tenfold tighter each time
      if (k + 1 < list.size()) CHECK(list[k].second > 1e-5);                       // it stops at the first that lands
    }
    CHECK(list.back().second <= 1e-5);
  }
  // Every method has its line in the summary.
  const std::size_t summary = r.out.find("fastest run on 1 thread with error <= 1e-05 m");
  REQUIRE(summary != std::string::npos);
  for (const char* method : {"dopri5 ", "tirk-newton ", "cvode-klu "})
    CHECK(r.out.find(std::string("chain6 W=1e+04           ") + method, summary) != std::string::npos);
  fs::remove_all(fs::path(b.dir).parent_path());
}

TEST_CASE("cli bench ivp: work-precision against CVODE on Robertson and eq. 11, CSV, summary and plot", "[cli][bench]") {
  const std::string dir = scratch("bench_ivp").string();
  const Result r = run("bench ivp --problems robertson,b1 --tolerances 1e-4,1e-6 --csv ivp.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("robertson: reference Test Set for IVP Solvers, problem ROBER") != std::string::npos);
  CHECK(r.out.find("b1: exact solution") != std::string::npos);
  CHECK(r.out.find("time / CVODE's time at equal correct digits") != std::string::npos);
  CHECK(r.out.find("compared   median     best    worst") != std::string::npos);
  std::istringstream csv(read_text(fs::path(dir) / "ivp.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line == "problem,n,solver,threads,rtol,ok,seconds,scd,steps,rejected,rhs_evaluations,jacobians,factorizations,note");
  int rows = 0, cvode = 0;
  while (std::getline(csv, line)) {
    ++rows;
    const std::vector<std::string> cells = csv_cells(line);
    REQUIRE(cells.size() >= 13);
    INFO(line);
    CHECK(cells[5] == "1");  // every run succeeds
    // mbsflow's methods: correct digits at least those asked for less one (rtol 1e-4: 3
    // digits). CVODE is the peer, not under test (it gets fewer than asked on b1).
    if (cells[2] != "cvode-bdf") CHECK(std::stod(cells[7]) >= -std::log10(std::stod(cells[4])) - 1);
    CHECK(std::stol(cells[11]) >= 1);  // Jacobians counted
    cvode += cells[2] == "cvode-bdf";
  }
  // 2 problems x (4 methods x 2 tolerances + CVODE at 4 tolerances: two decades below the tightest too)
  CHECK(rows == 2 * (4 * 2 + 4));
  CHECK(cvode == 8);
  const std::string python = MBSFLOW_PYTHON;
  const int plot = std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot_work_precision.py' '" + dir + "/ivp.csv' -o '" + dir +
                                "/ivp.png' >/dev/null")
                                   .c_str());
  CHECK(plot == 0);
  CHECK(fs::file_size(fs::path(dir) / "ivp.png") > 10000);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench ivp --atol-ratio 1: silent wrong answers are counted, CVODE's too", "[cli][bench]") {
  // atol = rtol = 1e-4 on Robertson: the second component (< 3.7e-5) has no control, and
  // CVODE ends "ok" with y1 grown far below zero (no correct digit) at every tolerance of
  // its range; tirk-newton, whose Newton iteration runs to RADAU5's tighter test on a
  // small system, ends with a correct digit at this one (with atol = 1e-4 and rtol 1e-3 or
  // 1e-6 it does not, and warns as docs/methods.md, "Tolerances", says).
  const std::string dir = scratch("bench_ivp_scalar").string();
  const Result r = run("bench ivp --problems robertson --atol-ratio 1 --tolerances 1e-4 --methods tirk-newton,cvode-bdf --csv ivp.csv",
                       dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("atol = 1 rtol for every component (--atol-ratio)") != std::string::npos);
  std::istringstream table(r.out);
  std::string line;
  int wrong_rows = 0;
  while (std::getline(table, line)) {
    std::istringstream cells(line);
    std::string problem, method, threads, ok, wrong;
    if (!(cells >> problem >> method >> threads >> ok >> wrong) || problem != "robertson" || ok.find('/') == std::string::npos) continue;
    INFO(line);
    if (method == "cvode-bdf")
      CHECK(std::stol(wrong) >= 1);  // a run that ended without an error, not one digit right
    else
      CHECK(wrong == "0");
    ++wrong_rows;
  }
  CHECK(wrong_rows == 2);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench load: a chain and a grid generated and started in their own processes with time and peak memory", "[cli][bench]") {
  const std::string dir = scratch("bench_load").string();
  const Result r = run("bench load --bodies 200,2000 --csv load.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("chain: load+start time ~ N^") != std::string::npos);
  CHECK(r.out.find("grid: load+start time ~ N^") != std::string::npos);
  std::istringstream csv(read_text(fs::path(dir) / "load.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line == "model,bodies,generate_s,generate_peak_MB,load_start_s,load_start_peak_MB");
  std::vector<std::string> models;
  std::vector<double> peaks;
  while (std::getline(csv, line)) {
    const std::vector<std::string> cells = csv_cells(line);
    REQUIRE(cells.size() == 6);
    models.push_back(cells[0] + " " + cells[1]);
    CHECK(std::stod(cells[4]) > 0.0);
    peaks.push_back(std::stod(cells[5]));
  }
  // The grid is the nearest square; the peak is each run's own, so it grows with the model.
  CHECK(models == std::vector<std::string>{"chain 200", "chain 2000", "grid 196", "grid 2025"});
  REQUIRE(peaks.size() == 4);
  CHECK(peaks[1] > peaks[0]);
  CHECK(peaks[3] > peaks[2]);
  // Nothing of the runs is left behind.
  for (const auto& e : fs::directory_iterator(dir)) CHECK(e.path().filename() == "load.csv");
  CHECK(run("bench load --dir no-such-folder", dir).code == 2);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench parallel: threads by doubling and worker processes with the predicted efficiency", "[cli][bench]") {
  const std::string dir = scratch("bench_parallel").string();
  const Result r = run("bench parallel --bodies 600 --threads 3 --processes 2 --executors flow --repeats 1 --csv par.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  std::istringstream csv(read_text(fs::path(dir) / "par.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line ==
        "bodies,executor,threads,partitions,steps,wall_s,s_per_simulated_s,speedup,efficiency,wait_fraction,"
        "predicted_speedup,predicted_efficiency");
  std::vector<std::string> runs;
  while (std::getline(csv, line)) {
    const std::vector<std::string> cells = csv_cells(line);
    REQUIRE(cells.size() == 12);
    runs.push_back(cells[1] + " " + cells[2]);
    CHECK(std::stod(cells[5]) > 0.0);
    const double predicted_speedup = std::stod(cells[10]), predicted_efficiency = std::stod(cells[11]);
    // The sequential run is its own prediction; a cut can only lose to imbalance and messages.
    if (cells[1] == "sequential") CHECK(predicted_speedup == 1.0);
    CHECK(predicted_efficiency > 0.0);
    CHECK(predicted_efficiency <= 1.0 + 1e-12);
    CHECK(predicted_speedup == Approx(predicted_efficiency * std::stod(cells[2])).epsilon(1e-4));
  }
  // Threads double up to the limit, which is taken too; processes run from 2.
  CHECK(runs == std::vector<std::string>{"sequential 1", "flow 1", "flow 2", "flow 3", "processes 2"});
  CHECK(r.out.find("alpha") != std::string::npos);
  CHECK(run("bench parallel --executors nowhere", dir).code != 0);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench rhs: nanoseconds per body with the roofline's bytes per body, bandwidth and peak", "[cli][bench]") {
  const std::string dir = scratch("bench_rhs").string();
  const Result r = run("bench rhs --bodies 300 --seconds 0.02 --csv rhs.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("roofline, one thread: this machine's triad bandwidth") != std::string::npos);
  std::istringstream csv(read_text(fs::path(dir) / "rhs.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line.find(",bytes_per_body,compiled_bytes_per_body,workspace_bytes_per_body,achieved_GB_s,triad_GB_s,peak_GFLOP_s,simd") !=
        std::string::npos);
  REQUIRE(std::getline(csv, line));
  const std::vector<std::string> cells = csv_cells(line);
  REQUIRE(cells.size() == 16);
  CHECK(cells[0] == "300");
  CHECK((cells[15] == "avx" || cells[15] == "sse2"));
  const double ns = std::stod(cells[2]), bytes = std::stod(cells[9]), compiled = std::stod(cells[10]),
               workspace = std::stod(cells[11]);
  CHECK(ns > 0.0);
  // One evaluation streams the state in and out (13 numbers a body each way), the compiled
  // model and the workspace written and read back.
  CHECK(bytes == Approx(2 * 13 * 8 + compiled + 2 * workspace));
  // Per body a compiled joint and the indices and lists around it; the chain's one joint
  // law and one body law are shared (shared_laws.hpp).
  CHECK(compiled > 30.0);
  CHECK(compiled < 120.0);
  CHECK(workspace > 100.0);
  CHECK(std::stod(cells[12]) == Approx(bytes / ns));
  CHECK(std::stod(cells[13]) > 0.0);
  CHECK(std::stod(cells[14]) > 0.0);
  CHECK(r.out.find("examples with rigid joints: not in examples/models") != std::string::npos);  // run outside the sources

  // The examples with rigid joints: right-hand side, analytic Jacobian and differences.
  const Result rigid =
      run("bench rhs --bodies 300 --seconds 0.02 --csv rhs.csv --dir " + std::string(MBSFLOW_SOURCE) + "/examples/models", dir, true);
  INFO(rigid.err << rigid.out);
  REQUIRE(rigid.code == 0);
  std::istringstream table(read_text(fs::path(dir) / "rhs_rigid.csv"));
  std::getline(table, line);
  CHECK(line == "model,bodies,equations,us_rhs,us_jacobian,us_differences,colours");
  int models = 0;
  while (std::getline(table, line)) {
    const std::vector<std::string> c = csv_cells(line);
    REQUIRE(c.size() == 7);
    CHECK(std::stoi(c[2]) == 13 * std::stoi(c[1]));  // 13 state numbers a body
    CHECK(std::stod(c[3]) > 0.0);
    CHECK(std::stod(c[4]) > 0.0);
    CHECK(std::stod(c[5]) > 0.0);
    CHECK(std::stoi(c[6]) <= std::stoi(c[2]));
    ++models;
  }
  CHECK(models == 3);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench beams: cost per element, a cantilever through RK4 and tirk, the spin-up's work-precision", "[cli][bench]") {
  const std::string dir = scratch("bench_beams").string();
  const Result r = run("bench beams --bodies 40 --seconds 0.01 --t-end 0.001 --tolerances 1e-3,1e-5 --csv beams.csv --dir " +
                           std::string(MBSFLOW_SOURCE) + "/examples/models",
                       dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  std::istringstream csv(read_text(fs::path(dir) / "beams.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line == "part,case,elements,method,tol,steps,factorizations,seconds,value");
  std::map<std::string, double> value;  // part/case/method/tol -> value
  int rows = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> c = csv_cells(line);
    REQUIRE(c.size() == 9);
    value[c[0] + "/" + c[1] + "/" + c[3] + "/" + c[4]] = std::stod(c[8]);
    ++rows;
  }
  CHECK(rows == 4 + 2 + 4);
  CHECK(value.at("cost/beam rhs//") > 0.0);
  CHECK(value.at("cost/chain jacobian//") > 0.0);
  // RK4 at its stable step and tirk reach the same tip deflection under gravity.
  const double rk4 = value.at("cantilever//rk4/0"), tirk = value.at("cantilever//tirk/0.0001");
  CHECK(rk4 < 0.0);
  CHECK(tirk == Approx(rk4).epsilon(1e-3));
  // Tighter tolerances, smaller errors (against the tirk reference at 1e-10).
  CHECK(value.at("spin-up//tirk/1e-05") < 0.1 * value.at("spin-up//tirk/0.001"));
}
