// Faults an unlucky user meets (the findings of issue 21, replayed): a second run on the
// same results file, kill -9 at any moment, settings that cannot be counted.
#include <catch2/catch.hpp>
#include <thread>

#include "process_support.hpp"

using namespace mbsflow::test;

namespace {

// Rows of a results file as h5py (a real reader, not ours) reads them; -1 if it cannot.
long rows_read_by_h5py(const fs::path& h5) {
  const std::string script =
      "import h5py,sys\n"
      "try:\n"
      "    f = h5py.File(sys.argv[1], 'r')\n"
      "except OSError:\n"  // killed in SWMR mode: marked open for writing, read as SWMR
      "    f = h5py.File(sys.argv[1], 'r', swmr=True)\n"
      "t = f['time'][:]\n"
      "p = f['bodies/position']\n"
      "assert p.shape[0] >= len(t), (p.shape, len(t))\n"  // times are written last
      "assert all(t[1:] > t[:-1])\n"
      "print(len(t))\n";
  const fs::path py = h5.parent_path() / "rows.py", out = h5.parent_path() / "rows.txt";
  std::ofstream(py) << script;
  const int code = std::system(("'" MBSFLOW_PYTHON "' '" + py.string() + "' '" + h5.string() + "' > '" + out.string() + "' 2>&1").c_str());
  INFO(read_text(out));
  return code == 0 ? std::stol(read_text(out)) : -1;
}

}  // namespace

TEST_CASE("a second run with the same -o is refused, and the first run's file stays whole", "[apps][faults]") {
  const fs::path d = scratch("same_output");
  REQUIRE(run("generate chain --bodies 100 -o chain.json", d.string()).code == 0);
  Child first({"run", "chain.json", "--t-end", "1000", "-o", "run.h5"}, d, "first");
  const auto start = std::chrono::steady_clock::now();
  while (!fs::exists(d / "run.h5") && std::chrono::steady_clock::now() - start < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(fs::exists(d / "run.h5"));
  const Result second = run("run chain.json --t-end 1 -o run.h5", d.string());
  CHECK(second.code == 2);
  CHECK_THAT(second.err, Catch::Contains("another run is writing the results file run.h5"));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // at least one periodic flush
  first.kill(SIGTERM);
  REQUIRE(first.wait(10.0));
  CHECK(rows_read_by_h5py(d / "run.h5") > 0);
  // Once the first has ended, the file may be written again.
  CHECK(run("run chain.json --t-end 0.01 -o run.h5", d.string()).code == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("kill -9 at any moment leaves no results file or a readable one", "[apps][faults]") {
  const fs::path d = scratch("kill9");
  REQUIRE(run("generate chain --bodies 2000 -o chain.json", d.string()).code == 0);
  // Moments before the file appears (reading the model, building the run) and after it,
  // measured from its appearance so that a slow build (sanitizers) meets them too.
  long readable = 0;
  for (const auto& [after_file, ms] : std::vector<std::pair<bool, int>>{
           {false, 30}, {false, 120}, {false, 300}, {true, 0}, {true, 50}, {true, 300}, {true, 900}, {true, 1700}}) {
    fs::remove(d / "run.h5");
    Child run9({"run", "chain.json", "--t-end", "1000", "-o", "run.h5"}, d, "run");
    if (after_file) {
      const auto start = std::chrono::steady_clock::now();
      while (!fs::exists(d / "run.h5") && std::chrono::steady_clock::now() - start < std::chrono::seconds(120))
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    run9.kill(SIGKILL);
    REQUIRE(run9.wait(10.0));
    INFO("killed " << ms << " ms after " << (after_file ? "the file appeared" : "the start"));
    if (!fs::exists(d / "run.h5")) {  // killed before the layout was on disk: the path was never touched
      CHECK_FALSE(after_file);
      continue;
    }
    CHECK(rows_read_by_h5py(d / "run.h5") >= 0);
    ++readable;
  }
  CHECK(readable >= 5);
  fs::remove_all(d.parent_path());
}

TEST_CASE("a step count that cannot be represented is an input error, not a negative done", "[apps][faults]") {
  const fs::path d = scratch("step_count");
  REQUIRE(run("generate chain --bodies 3 -o chain.json", d.string()).code == 0);
  const Result r = run("run chain.json --step 1e-300 -o run.h5", d.string());
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--step 1e-300") && Catch::Contains("more than a run can take"));
  CHECK_FALSE(fs::exists(d / "run.h5"));
  fs::remove_all(d.parent_path());
}
