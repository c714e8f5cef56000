// End-to-end tests of the mbsflow command line: exit codes and messages.
#include <algorithm>
#include <catch2/catch.hpp>

#include "cli_support.hpp"

using namespace mbsflow::test;


TEST_CASE("every bad model file gives its exact message and exit code 2", "[apps]") {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(MBSFLOW_BAD_MODELS))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 20);
  for (const fs::path& f : files) {
    fs::path expected = f;
    expected.replace_extension(".expected");
    REQUIRE(fs::exists(expected));
    const Result r = run("run " + f.filename().string(), MBSFLOW_BAD_MODELS);
    INFO(f.filename().string());
    CHECK(r.code == 2);
    CHECK(trim(r.err) == trim(read_text(expected)));
  }
}

TEST_CASE("usage errors exit with 2, help with 0", "[apps]") {
  CHECK(run("--help").code == 0);
  CHECK(run("").code == 2);
  CHECK(run("frobnicate").code == 2);
  CHECK(run("run").code == 2);
  CHECK(run("run model.json --method euler").code == 2);
  CHECK(run("run model.json --step -1").code == 2);
  const Result missing = run("run does-not-exist.json");
  CHECK(missing.code == 2);
  CHECK(trim(missing.err) == "does-not-exist.json: cannot open the model file");
  CHECK(run("generate chain --bodies 0").code == 2);
  CHECK(run("generate cube").code == 2);
}

TEST_CASE("generated chain, grid and train models run to the end", "[apps]") {
  const fs::path d = scratch("generate");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 30 -o chain.json", dir).code == 0);
  REQUIRE(run("generate grid --rows 4 --cols 5 -o grid.json", dir).code == 0);
  REQUIRE(run("generate train --wagons 2 -o train.json", dir).code == 0);
  const Result chain = run("run chain.json --t-end 0.2", dir, true);
  CHECK(chain.code == 0);
  CHECK(chain.err.find("no step given: RK4 with the stability estimate") != std::string::npos);
  CHECK(chain.out.find("model chain-30: 30 bodies, 30 joints") != std::string::npos);
  CHECK(run("run grid.json --t-end 0.1 --method dopri5 --rtol 1e-5 --quiet", dir).code == 0);
  // The implicit methods say where their first step and their Jacobian come from.
  const Result implicit = run("run chain.json --t-end 0.05 --method tirk --rtol 1e-4 --atol 1e-4", dir, true);
  CHECK(implicit.code == 0);
  CHECK(implicit.err.find("tirk picks its first step from the tolerances") != std::string::npos);
  CHECK(implicit.err.find("analytic Jacobian") != std::string::npos);
  const Result differenced = run("run chain.json --t-end 0.05 --method tirk --jacobian differences", dir, true);
  CHECK(differenced.code == 0);
  CHECK(differenced.err.find("Jacobian by coloured differences (--jacobian differences)") != std::string::npos);
  const Result train = run("run train.json --t-end 0.5 --every 5 --output train.h5", dir);
  CHECK(train.code == 0);
  CHECK(train.err.find("in train.h5") != std::string::npos);
  CHECK(fs::exists(d / "train.xdmf"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("run --output-interval: the snapshots follow model time, whatever the method", "[apps]") {
  const fs::path d = scratch("interval");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 8 -o chain.json", dir).code == 0);
  for (const char* method : {"rk4", "dopri5"}) {
    INFO(method);
    const Result r = run(std::string("run chain.json --t-end 0.1 --output-interval 0.01 -o out.h5 --method ") + method, dir);
    CHECK(r.code == 0);
    CHECK(r.err.find(", 11 snapshots,") != std::string::npos);
  }
  const Result rk4 = run("run chain.json --t-end 0.1 --output-interval 0.01", dir);
  CHECK(rk4.err.find("to fit the output interval") != std::string::npos);
  CHECK(run("run chain.json --t-end 0.1 --output-interval 0.01 --every 3", dir).code == 2);
  const Result odd = run("run chain.json --t-end 0.1 --step 3e-4 --output-interval 0.001", dir);
  CHECK(odd.code == 2);
  CHECK(odd.err.find("not a whole number of rk4 steps") != std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("a run that diverges exits with 1 and names time, body and a step that works", "[apps]") {
  const fs::path d = scratch("diverge");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 10 --step 0.01 -o chain.json", dir).code == 0);
  const Result r = run("run chain.json --t-end 1 -o diverged.h5", dir);
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK(r.err.find("in diverged.h5") != std::string::npos);
  CHECK(r.err.find("warning: step 0.01 s is above the estimated RK4 stability limit") != std::string::npos);
  CHECK(r.err.find("mbsflow: run diverged at t = ") != std::string::npos);
  CHECK(r.err.find("body 'link") != std::string::npos);
  CHECK(r.err.find("try --step ") != std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("run reports its peak memory per body and the fixed part of it thins out with size", "[cli]") {
  const fs::path d = scratch("peak-memory");
  const std::string dir = d.string();
  const auto per_body = [&](int bodies) {
    REQUIRE(run("generate chain --bodies " + std::to_string(bodies) + " -o c.json", dir).code == 0);
    const Result r = run("run c.json --t-end 1e-4 --threads 1 -o c.h5", dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::size_t at = r.err.find("; peak memory ");
    REQUIRE(at != std::string::npos);
    const std::size_t open = r.err.find('(', at), close = r.err.find(" B per body)", at);
    REQUIRE(close != std::string::npos);
    const double b = std::stod(r.err.substr(open + 1, close - open - 1));
    // The total printed before it, in MiB here, agrees to its 3 digits.
    const double mib = std::stod(r.err.substr(at + 14));
    CHECK(b * bodies / 1048576.0 == Approx(mib).epsilon(0.01));
    return b;
  };
  const double small = per_body(2000), large = per_body(20000);
  CHECK(small > 0.0);
  CHECK(large < small);
  // A small model's peak is the program's own, not its bodies': no figure per body.
  REQUIRE(run("generate chain --bodies 3 -o c.json", dir).code == 0);
  const Result tiny = run("run c.json --t-end 1e-4 --threads 1 -o c.h5", dir);
  CHECK(tiny.err.find("; peak memory ") != std::string::npos);
  CHECK(tiny.err.find("B per body") == std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("run --timings names each set-up phase and says whether malloc has huge pages", "[apps]") {
  const std::string dir = scratch("timings").string();
  REQUIRE(run("generate chain --bodies 200 -o chain.json", dir).code == 0);
  const Result r = run("run chain.json --t-end 0.01 --threads 2 -q --timings -o chain.h5", dir);
  REQUIRE(r.code == 0);
  for (const char* phase : {"read the model file", "parse and check the model", "stable step and options",
                            "open the results file", "cut into submodels", "build the submodels and the whole system",
                            "start the results file", "steps, and the results written", "the run's end"})
    CHECK(r.err.find(phase) != std::string::npos);
  // Resident memory per body on the phases after reading: a number of bytes.
  const std::size_t parse = r.err.find("parse and check the model");
  const std::string line = r.err.substr(parse, r.err.find('\n', parse) - parse);
  CHECK(std::stod(line.substr(line.find_last_of(' ') + 1)) > 0.0);
  // mbsflow restarts itself with glibc's huge-page tunable where the kernel gives them, for
  // a model file of 16 MiB or more (this one padded with spaces to that size) or when
  // MBSFLOW_HUGE_PAGES=1 asks; a small model's run starts once.
  CHECK(r.err.find("transparent huge pages: off (a model file under 16 MiB") != std::string::npos);
  const std::string modes = read_text("/sys/kernel/mm/transparent_hugepage/enabled");
  const bool kernel = modes.find("[always]") != std::string::npos || modes.find("[madvise]") != std::string::npos;
  const char* expected = kernel ? "transparent huge pages: on" : "transparent huge pages: off";
  {
    std::ofstream padded(fs::path(dir) / "padded.json");
    padded << read_text(fs::path(dir) / "chain.json") << std::string(std::size_t{16} << 20, ' ');
  }
  CHECK(run("run padded.json --t-end 0.01 -q --timings", dir).err.find(expected) != std::string::npos);
  ::setenv("MBSFLOW_HUGE_PAGES", "1", 1);
  CHECK(run("run chain.json --t-end 0.01 -q --timings", dir).err.find(expected) != std::string::npos);
  ::setenv("MBSFLOW_HUGE_PAGES", "0", 1);
  const Result off = run("run chain.json --t-end 0.01 -q --timings", dir);
  ::unsetenv("MBSFLOW_HUGE_PAGES");
  CHECK(off.code == 0);
  CHECK(off.err.find("transparent huge pages: off") != std::string::npos);
  // A tunable the caller set is left as it is.
  ::setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=0", 1);
  ::setenv("MBSFLOW_HUGE_PAGES", "1", 1);
  const Result theirs = run("run chain.json --t-end 0.01 -q --timings", dir);
  ::unsetenv("MBSFLOW_HUGE_PAGES");
  ::unsetenv("GLIBC_TUNABLES");
  CHECK(theirs.err.find("transparent huge pages: off") != std::string::npos);
  // Without results or checkpoints a partitioned run builds no whole system; its final
  // state, as the summary prints it, is the one-thread run's.
  const Result bare = run("run chain.json --t-end 0.01 --threads 2 --timings", dir, true);
  REQUIRE(bare.code == 0);
  CHECK(bare.err.find("build the submodels ") != std::string::npos);
  CHECK(bare.err.find("the whole system") == std::string::npos);
  const Result one = run("run chain.json --t-end 0.01 --threads 1", dir, true);
  REQUIRE(one.code == 0);
  CHECK(bare.out.find("final state of the first 10 bodies") != std::string::npos);
  CHECK(bare.out == one.out);
}
