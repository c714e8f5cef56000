// mbsflow bench stiff end to end on a small chain: every method runs, CVODE included,
// each row has a finite error against the reference, and the work-precision plot draws it.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <sstream>
#include <string>

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
    std::vector<std::string> cells;
    std::istringstream cs(line);
    for (std::string cell; std::getline(cs, cell, ',');) cells.push_back(cell);
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
