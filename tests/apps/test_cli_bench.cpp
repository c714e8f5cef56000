// mbsflow bench stiff end to end on a small chain: every method runs, CVODE included,
// each row has a finite error against the reference, and the work-precision plot draws it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"

using namespace mbsflow::test;

TEST_CASE("cli bench stiff: a stiff chain against RK4, DOPRI5 and CVODE, CSV and plot", "[cli][bench]") {
  const std::string dir = scratch("bench_stiff").string();
  const Result r = run("bench stiff --problems chain --bodies 6 --frequencies 1e4 --t-end 0.02 --tolerances 1e-3 "
                       "--threads 1 --csv stiff.csv",
                       dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("fastest run on 1 thread with error <= 1e-03 m") != std::string::npos);
  std::istringstream csv(read_text(fs::path(dir) / "stiff.csv"));
  std::string line;
  std::getline(csv, line);
  CHECK(line == "model,method,threads,tol,steps,evaluations,jacobians,factorizations,wall_s,error_m,note");
  int rows = 0;
  std::string methods;
  while (std::getline(csv, line)) {
    ++rows;
    const std::vector<std::string> cells = csv_cells(line);
    REQUIRE(cells.size() >= 10);
    methods += cells[1] + " ";
    const double error = std::stod(cells[9]);
    INFO(line);
    CHECK(error < 1e-2);  // every method at 1e-3 lands well within a centimetre on this chain
    if (cells[1].rfind("tirk", 0) == 0 || cells[1] == "colloc") CHECK(std::stol(cells[6]) >= 1);  // Jacobians counted
  }
  CHECK(rows == 7);
  CHECK(methods == "reference rk4 dopri5 tirk-newton tirk-newton-triangular colloc cvode-klu ");
  const std::string python = MBSFLOW_PYTHON;
  const int plot = std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot_work_precision.py' '" + dir +
                                "/stiff.csv' -o '" + dir + "/stiff.png' >/dev/null")
                                   .c_str());
  CHECK(plot == 0);
  CHECK(fs::file_size(fs::path(dir) / "stiff.png") > 10000);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli bench ivp: work-precision against CVODE on Robertson and eq. 11, CSV, summary and plot", "[cli][bench]") {
  const std::string dir = scratch("bench_ivp").string();
  const Result r = run("bench ivp --problems robertson,b1 --tolerances 1e-4,1e-6 --csv ivp.csv", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("robertson: reference Test Set for IVP Solvers, problem ROBER") != std::string::npos);
  CHECK(r.out.find("b1: exact solution") != std::string::npos);
  CHECK(r.out.find("time / CVODE's time at equal correct digits") != std::string::npos);
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
