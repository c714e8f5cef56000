// Loose coupling from the command line.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "cli_support.hpp"
#include "mbsflow/io/results_file.hpp"

using namespace mbsflow::test;

namespace {
// Largest entry-wise difference of two datasets of the same size.
double largest_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double gap = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) gap = std::max(gap, std::abs(a[i] - b[i]));
  return gap;
}
}  // namespace

TEST_CASE("run --coupling loose writes results close to the tight run and reports the coupling error", "[apps][loose]") {
  const fs::path d = scratch("loose");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 60 -o chain.json", dir).code == 0);
  REQUIRE(run("run chain.json --t-end 0.05 --step 1e-4 --every 100 -q -o tight.h5", dir).code == 0);
  const Result r = run("run chain.json --t-end 0.05 --step 1e-4 --every 100 --threads 2 --partitions 3 "
                       "--coupling loose --macro-step 2e-4 --extrapolation 2 -o loose.h5", dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("3 submodels on 2 threads, loosely coupled: macro step 0.0002 s (") != std::string::npos);
  CHECK(r.err.find("extrapolation order 2, overlap 0.0002 s") != std::string::npos);
  CHECK(r.err.find("coupling error over 250 macro steps: ghost positions off by at most ") != std::string::npos);
  const mbsflow::ResultsFile tight((d / "tight.h5").string()), loose((d / "loose.h5").string());
  REQUIRE(loose.time().size() == tight.time().size());
  for (std::size_t i = 0; i < tight.time().size(); ++i) CHECK(std::abs(loose.time()[i] - tight.time()[i]) < 1e-12);
  const std::vector<double> a = tight.read("/bodies/position"), b = loose.read("/bodies/position");
  const double gap = largest_difference(a, b);
  CHECK(gap < 1e-5);
  CHECK(gap > 0.0);  // loosely coupled: close, not the same

  // Defaults: 16 stable steps, an overlap of one macro step, error control.
  const Result defaults = run("run chain.json --t-end 0.05 --coupling loose --threads 2 --partitions 2", dir);
  INFO(defaults.err);
  CHECK(defaults.code == 0);
  CHECK(defaults.err.find("2 submodels on 2 threads, loosely coupled: macro step 0.01099 s (10.8 x the cut joints' RK4 "
                          "stable step), extrapolation order 1, overlap 0.01099 s (") != std::string::npos);
  CHECK(defaults.err.find(" bodies borrowed), error control") != std::string::npos);
  const Result adaptive = run("run chain.json --t-end 0.05 --coupling loose --coupling-tol 1e-9 --overlap 0.002 --threads 2 --partitions 2", dir);
  INFO(adaptive.err);
  CHECK(adaptive.code == 0);
  CHECK(adaptive.err.find(" taken again") != std::string::npos);
  const Result h_only = run("run chain.json --macro-step 1e-3", dir);
  CHECK(h_only.code == 2);
  CHECK(h_only.err.find("--macro-step, --coupling-tol, --max-lag, --exact-lag, --submodel-methods, --overlap: only with "
                        "--coupling loose") != std::string::npos);
  // Across processes: the same numbers as in one process; a slow network changes nothing.
  const std::string common = "run chain.json --t-end 0.05 --step 1e-4 --every 100 --partitions 3 -q --coupling loose "
                             "--macro-step 2e-4 --extrapolation 2 -o ";
  REQUIRE(run(common + "loose-procs.h5 --processes 2 --exchange-delay 0.001", dir).code == 0);
  const mbsflow::ResultsFile procs((d / "loose-procs.h5").string());
  CHECK(procs.time() == loose.time());
  // The coupling error of every macro step, the same across processes.
  const std::vector<double> index = loose.read("/coupling/index"), error = loose.read("/coupling/position_error");
  REQUIRE(index.size() == 250);
  CHECK(index.front() == 1.0);
  CHECK(index.back() == 250.0);
  CHECK(std::abs(loose.read("/coupling/t_end").back() - 0.05) < 1e-12);
  CHECK(*std::max_element(error.begin(), error.end()) > 0.0);
  CHECK(*std::max_element(error.begin(), error.end()) < 1e-6);
  const std::vector<double> lags = loose.read("/coupling/lag");
  CHECK(*std::max_element(lags.begin(), lags.end()) == 0.0);
  CHECK(procs.read("/coupling/position_error") == error);
  CHECK(procs.read("/coupling/velocity_error") == loose.read("/coupling/velocity_error"));
  CHECK(procs.read("/bodies/position") == b);
  CHECK(procs.read("/bodies/velocity") == loose.read("/bodies/velocity"));
  REQUIRE(run("run chain.json --t-end 0.05 --step 1e-4 --every 100 -q --processes 2 --exchange-delay 0.001 -o tight-delay.h5",
              dir).code == 0);
  CHECK(mbsflow::ResultsFile((d / "tight-delay.h5").string()).read("/bodies/position") == a);
  // Error control across processes: every worker takes the same macro steps, again where
  // the largest error over all says so; the numbers of the one-process run.
  const Result adapt = run(common + "adapt-threads.h5 --threads 2 --coupling-tol 1e-9", dir);
  INFO(adapt.err);
  REQUIRE(adapt.code == 0);
  REQUIRE(run(common + "adapt-procs.h5 --processes 2 --coupling-tol 1e-9 --exchange-delay 0.001", dir).code == 0);
  const mbsflow::ResultsFile adapt_threads((d / "adapt-threads.h5").string()), adapt_procs((d / "adapt-procs.h5").string());
  CHECK(adapt_threads.read("/coupling/t_end").size() > 250);  // macro steps taken again, shorter
  CHECK(adapt_procs.read("/coupling/t_end") == adapt_threads.read("/coupling/t_end"));
  CHECK(adapt_procs.read("/coupling/position_error") == adapt_threads.read("/coupling/position_error"));
  CHECK(adapt_procs.read("/bodies/position") == adapt_threads.read("/bodies/position"));
  CHECK(run("run chain.json --exchange-delay 0.01", dir).code == 2);
  CHECK(run("run chain.json --max-lag 1", dir).code == 2);
  REQUIRE(run(common + "lag-threads.h5 --threads 2 --max-lag 2 --exact-lag", dir).code == 0);
  REQUIRE(run(common + "lag-procs.h5 --processes 2 --max-lag 2 --exact-lag --exchange-delay 0.001", dir).code == 0);
  CHECK(mbsflow::ResultsFile((d / "lag-threads.h5").string()).read("/bodies/position") ==
        mbsflow::ResultsFile((d / "lag-procs.h5").string()).read("/bodies/position"));
  CHECK(run("run chain.json --coupling loose --macro-step 1e-3 --extrapolation 3", dir).code == 2);
  const Result lag_tol = run("run chain.json --coupling loose --max-lag 1 --coupling-tol 1e-6", dir);
  CHECK(lag_tol.code == 2);  // the library names its settings; the CLI shows them as flags
  CHECK(lag_tol.err.find("\n--max-lag: needs a fixed macro step (not with --coupling-tol)\n") != std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("run --coupling loose: newest values with a lag over a slow network, a method per submodel", "[apps][loose]") {
  const fs::path d = scratch("loose-async");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 60 -o chain.json", dir).code == 0);
  REQUIRE(run("run chain.json --t-end 0.05 --step 1e-4 --every 100 -q -o tight.h5", dir).code == 0);
  const std::string common = "run chain.json --t-end 0.05 --step 1e-4 --every 100 --partitions 3 --coupling loose "
                             "--macro-step 2e-4 --extrapolation 2 ";
  // Messages 20 ms late and macro steps of microseconds: the submodels run ahead on older
  // values, never more than 2 macro steps. H is 0.15 of the stable step: at 0.3 of it,
  // lags that jump between 0 and 2 (slow builds, sanitizers) made the chain ring up to
  // 0.2 m off, while a steady lag of 2 stays within 1e-5 (notes/parallel-measurements.md).
  const Result r = run("run chain.json --t-end 0.05 --step 1e-4 --every 100 --partitions 3 --coupling loose "
                       "--macro-step 1e-4 --extrapolation 2 --processes 2 --exchange-delay 0.02 --max-lag 2 -o async.h5", dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("macro steps from older values, at most 2 steps old") != std::string::npos);
  const mbsflow::ResultsFile tight((d / "tight.h5").string()), async((d / "async.h5").string());
  const std::vector<double> lags = async.read("/coupling/lag");
  REQUIRE(lags.size() == 500);
  CHECK(*std::max_element(lags.begin(), lags.end()) == 2.0);
  const std::vector<double> a = tight.read("/bodies/position"), b = async.read("/bodies/position");
  REQUIRE(a.size() == b.size());
  CHECK(largest_difference(a, b) < 1e-4);

  // RK4 in the outer submodels, DOPRI5 (its own steps) in the middle one.
  const Result mixed = run(common + "--threads 2 --submodel-methods rk4,dopri5,rk4 --rtol 1e-8 --atol 1e-10 -o mixed.h5", dir);
  INFO(mixed.err);
  REQUIRE(mixed.code == 0);
  const std::vector<double> c = mbsflow::ResultsFile((d / "mixed.h5").string()).read("/bodies/position");
  REQUIRE(c.size() == a.size());
  const double mixed_gap = largest_difference(a, c);
  CHECK(mixed_gap < 1e-5);
  CHECK(mixed_gap > 0.0);
  const Result bad = run(common + "--submodel-methods rk4,dopri5", dir);
  CHECK(bad.code == 2);
  CHECK(bad.err.find("one method per submodel: 3 submodels, 2 methods") != std::string::npos);
  CHECK(run(common + "--submodel-methods rk4,euler,rk4", dir).code == 2);
  CHECK(run(common + "--exact-lag", dir).code == 2);
  fs::remove_all(d.parent_path());
}
