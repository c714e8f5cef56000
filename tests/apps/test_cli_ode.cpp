// mbsflow ode end to end: the report, the results file and its plot, --describe, errors.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <regex>
#include <string>

#include "cli_support.hpp"

using namespace mbsflow::test;

namespace {
double reported(const std::string& out, const std::string& what) {
  std::smatch m;
  REQUIRE(std::regex_search(out, m, std::regex(what + " ([0-9.e+-]+)")));
  return std::stod(m[1]);
}
}  // namespace

TEST_CASE("cli ode: heat with step control reports the run, writes the file, and plots it", "[cli][ode]") {
  const std::string dir = scratch("ode").string();
  const Result r = run("ode --problem heat --n 2000 --s 3 --tol 1e-6 --threads 2 -o heat.h5", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(reported(r.out, "max error") <= 1e-5);
  CHECK(reported(r.out, "rhs evaluations") > 0);
  CHECK(r.out.find("(banded)") != std::string::npos);
  CHECK(fs::file_size(fs::path(dir) / "heat.h5") > 0);
  const std::string python = MBSFLOW_PYTHON;
  const int plot = std::system((python + " '" + MBSFLOW_SOURCE + "/scripts/plot.py' '" + dir + "/heat.h5' -o '" + dir +
                                "/heat.png' >/dev/null").c_str());
  CHECK(plot == 0);
  CHECK(fs::file_size(fs::path(dir) / "heat.png") > 10000);
  fs::remove_all(fs::path(dir).parent_path());
}

TEST_CASE("cli ode: the seed's functional iteration on eq. 10, and fixed steps", "[cli][ode]") {
  const Result f = run("ode --problem hnw --s 2 --iteration functional --tol 1e-8 -q", ".", true);
  INFO(f.err << f.out);
  REQUIRE(f.code == 0);
  CHECK(reported(f.out, "factorizations") == 0);
  const Result fixed = run("ode --problem b1 --s 2 --fixed-step 0.001 -q", ".", true);
  REQUIRE(fixed.code == 0);
  CHECK(reported(fixed.out, "steps") == 10000);
}

TEST_CASE("cli ode: --describe prints the seed's method with exact coefficients", "[cli][ode]") {
  const Result r = run("ode --describe --m 3 --s 2", ".", true);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("q = (55/136, 27/17, -135/136), d = (141/1360, 207/170, 297/170), g = (57/170, -9/1360)") != std::string::npos);
  CHECK(r.out.find("largest exact residual 0") != std::string::npos);
  CHECK(r.out.find("not zero-stable") != std::string::npos);
  const Result a = run("ode --describe --s 2", ".", true);
  CHECK(a.out.find("A-stable") != std::string::npos);
}

TEST_CASE("cli ode: bad input exits 2, a failed run exits 1", "[cli][ode]") {
  CHECK(run("ode --problem heat --s 3 --order 2").code == 2);  // order below s
  CHECK(run("ode --problem nope").code == 2);
  CHECK(run("ode --s 2").code == 2);  // no problem
  const Result fail = run("ode --problem hnw --s 3 --tol 1e-3");  // x2 drifts to its singularity near t = 1.93
  CHECK(fail.code == 1);
  CHECK(fail.err.find("step size underflow") != std::string::npos);
}
