// What a newcomer meets in the first hour: models that run with no flags, nothing changed
// behind their back, -o that never costs them a file, one clear line per mistake.
#include <sys/stat.h>

#include <catch2/catch.hpp>

#include "cli_support.hpp"

using namespace mbsflow::test;

namespace {

// A pendulum on a rigid revolute joint; `offset` moves the joint's point on the bob away
// from the pivot (m).
std::string pendulum(double offset = 0.0, const std::string& simulation = R"({"t_end": 2})") {
  return R"({"name": "pendulum", "gravity": [0, -9.81, 0],
  "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.001, 0.001, 0.001], "position": [1, 0, 0]}],
  "joints": [{"name": "pivot", "type": "revolute", "body1": "ground", "body2": "bob",
              "point1": [0, 0, 0], "point2": [)" +
         std::to_string(-1.0 + offset) + R"(, 0, 0], "axis1": [0, 0, 1]}],
  "simulation": )" + simulation + "}";
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

// The number in "N snapshots" of a run's closing line.
long snapshots(const std::string& err) {
  const std::size_t at = err.find(" snapshots, ");
  REQUIRE(at != std::string::npos);
  std::size_t from = err.rfind(' ', at - 1);
  return std::stol(err.substr(from + 1, at - from - 1));
}

}  // namespace

TEST_CASE("a pendulum on a rigid revolute runs with no flags: an adaptive method, said in one line", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-pendulum");
  write(d / "pendulum.json", pendulum());
  const Result r = run("run pendulum.json -o p.h5", d.string());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("no joint gives RK4 a stable step (no compliant joint): dopri5, adaptive, rtol 1e-06, atol 1e-08") !=
        std::string::npos);
  CHECK(r.err.find("give --step") == std::string::npos);
  // About a thousand snapshots over the run, not every step.
  CHECK(snapshots(r.err) == 1001);
  // RK4 named without a step: refused, saying what works instead.
  const Result rk4 = run("run pendulum.json --method rk4", d.string());
  CHECK(rk4.code == 2);
  CHECK(rk4.err.find("rk4 needs a step") != std::string::npos);
  CHECK(rk4.err.find("--method dopri5") != std::string::npos);
  CHECK(run("run pendulum.json --method rk4 --step 0.001 -q", d.string()).code == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("RK4's default output is about a thousand snapshots over the run, on whole steps", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-grid");
  REQUIRE(run("generate chain --bodies 10 -o chain.json", d.string()).code == 0);
  // The generator's model asks for every 100th step: that stays. Without output settings
  // in the model, about a thousand.
  std::string text = read_text(d / "chain.json");
  const std::size_t at = text.find("\"output_every\"");
  REQUIRE(at != std::string::npos);
  text.erase(at, text.find_first_of(",}", at) - at + (text[text.find_first_of(",}", at)] == ',' ? 1 : 0));
  write(d / "plain.json", text);
  const Result r = run("run plain.json --t-end 3 -o c.h5", d.string());
  INFO(r.err);
  REQUIRE(r.code == 0);
  const long n = snapshots(r.err);
  CHECK(n >= 500);  // every k-th step, k = ceil(steps / 1000): between 500 and 1001
  CHECK(n <= 1001);
  CHECK(r.err.find("a snapshot every ") != std::string::npos);
  // Asked for, every step it is.
  const Result every = run("run plain.json --t-end 0.01 --every 1 -o e.h5", d.string());
  CHECK(every.code == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("a rigid joint its bodies do not meet is refused, or assembled on request with the moves reported", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-assemble");
  write(d / "off.json", pendulum(0.5));
  const Result r = run("run off.json", d.string());
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("off.json: rigid joint 'pivot' is violated by 0.5") != std::string::npos);
  CHECK(r.err.find("--assemble") != std::string::npos);
  const Result assembled = run("run off.json --assemble -o a.h5", d.string());
  INFO(assembled.err);
  CHECK(assembled.code == 0);
  CHECK(assembled.err.find("--assemble moved 1 body onto the rigid joints: bob by 0.5 m") != std::string::npos);
  // Within the tolerance (1e-5), as given.
  write(d / "close.json", pendulum(1e-7));
  CHECK(run("run close.json -q", d.string()).code == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("results (-o) go only where nothing is or an mbsflow results file was, and leave no stray file", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-output");
  const std::string dir = d.string();
  write(d / "pendulum.json", pendulum(0.0, R"({"t_end": 0.1})"));
  const std::string model = read_text(d / "pendulum.json");
  auto refused = [&](const std::string& args, const std::string& says) {
    const Result r = run(args, dir);
    INFO(args << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(says) != std::string::npos);
  };
  refused("run pendulum.json -o pendulum.json", "is the input file pendulum.json");
  CHECK(read_text(d / "pendulum.json") == model);
  refused("run pendulum.json -o ''", "-o: give a file name");
  fs::create_directory(d / "folder");
  refused("run pendulum.json -o folder", "-o folder is a folder");
  CHECK(!fs::exists(d / "folder.part"));
  REQUIRE(::mkfifo((d / "fifo").c_str(), 0600) == 0);
  refused("run pendulum.json -o fifo", "-o fifo is a FIFO");  // refused at once, never opened
  refused("run pendulum.json -o /dev/null", "is a device");
  CHECK(fs::is_character_file("/dev/null"));
  write(d / "table.csv", "a,b\n1,2\n");
  refused("run pendulum.json -o table.csv", "exists and is not an mbsflow results file; give another name, or --force");
  CHECK(read_text(d / "table.csv") == "a,b\n1,2\n");
  refused("run pendulum.json -o no-such-folder/r.h5", "there is no folder no-such-folder");
  refused("ode --problem hnw -q -o table.csv", "not an mbsflow results file");
  // A results file is replaced; --force replaces another regular file.
  REQUIRE(run("run pendulum.json -q -o r.h5", dir).code == 0);
  CHECK(run("run pendulum.json -q -o r.h5", dir).code == 0);
  CHECK(run("ode --problem hnw -q -o r.h5", dir).code == 0);  // an ode results file over a run's
  CHECK(run("run pendulum.json -q -o table.csv --force", dir).code == 0);
  for (const auto& e : fs::directory_iterator(d)) CHECK(e.path().extension() != ".part");
  fs::remove_all(d.parent_path());
}

TEST_CASE("mistakes get one clear line that says what works instead", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-messages");
  const std::string dir = d.string();
  write(d / "pendulum.json", pendulum(0.0, R"({"t_end": 0.1})"));
  const Result typo = run("rn pendulum.json", dir);
  CHECK(typo.code == 2);
  CHECK(trim(typo.err).find("mbsflow: unknown command 'rn' (did you mean run?); the commands are run, ") == 0);
  const Result bench = run("bench", dir);
  CHECK(bench.code == 2);
  CHECK(!fs::exists(d / "bench_rhs.csv"));
  const Result plot_missing = run("plot missing.h5", dir);
  CHECK(plot_missing.code == 2);
  CHECK(trim(plot_missing.err) == "missing.h5: cannot open the results file");
  const Result plot_model = run("plot pendulum.json", dir);
  CHECK(plot_model.code == 2);
  CHECK(plot_model.err.find("Traceback") == std::string::npos);
  CHECK(plot_model.err.find("not an mbsflow results file") != std::string::npos);
  // One rigid piece on two processes: refused before any worker starts.
  const Result processes = run("run pendulum.json --processes 2", dir);
  CHECK(processes.code == 2);
  CHECK(processes.err.find("interrupted") == std::string::npos);
  CHECK(processes.err.find("--processes 2 needs as many submodels") != std::string::npos);
  REQUIRE(run("generate chain --bodies 6 -o chain.json", dir).code == 0);
  const Result tirk = run("run chain.json --t-end 0.01 --method tirk --processes 2", dir);
  CHECK(tirk.code == 2);
  CHECK(tirk.err.find("--coupling loose") != std::string::npos);
  const Result loose = run("run chain.json --t-end 0.01 --coupling loose --threads 1", dir);
  CHECK(loose.code == 0);
  CHECK(loose.err.find("--partitions N") != std::string::npos);
  CHECK(run("run chain.json --t-end 0.01 --threads 0 -q", dir).code == 0);  // 0: all cores, as in ode and Python
  const Result one = run("run pendulum.json", dir, true);
  CHECK(one.out.find("1 body, 1 joint;") != std::string::npos);
  CHECK(one.err.find("B per body") == std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("keygen makes the folder it writes into, owner-only", "[apps][first-hour]") {
  const fs::path d = scratch("first-hour-keygen");
  const Result r = run("keygen fresh/.mbsflow/cluster", d.string());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(fs::exists(d / "fresh/.mbsflow/cluster.key"));
  struct stat st {};
  REQUIRE(::stat((d / "fresh/.mbsflow").c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0700);
  fs::remove_all(d.parent_path());
}
