// End-to-end tests of multi-process runs: bitwise identity with the one-process run, and
// what happens when a worker or the coordinator dies or the set-up is wrong. Every process
// runs on 127.0.0.1 and is started and stopped by the test.
#include <catch2/catch.hpp>
#include <fstream>

#include "cli_support.hpp"
#include "process_support.hpp"

using namespace mbsflow::test;
using Clock = std::chrono::steady_clock;

namespace {

// Workers started by the test, listening on free loopback ports.
struct Workers {
  std::vector<std::unique_ptr<Child>> procs;
  std::vector<std::string> endpoints;
  Workers(int n, const fs::path& dir, const std::vector<std::string>& extra = {}, const std::string& name = "w") {
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> args{"worker", "--listen", "tcp://127.0.0.1:*", "--threads", "1", "--insecure"};
      args.insert(args.end(), extra.begin(), extra.end());
      procs.push_back(std::make_unique<Child>(args, dir, name + std::to_string(i)));
      endpoints.push_back(procs.back()->endpoint());
      REQUIRE(!endpoints.back().empty());
    }
  }
};

void write_cluster(const fs::path& file, const std::vector<std::string>& endpoints, const std::string& timeouts = "") {
  std::ofstream f(file);
  f << "{\n  \"transport\": \"tcp\",\n" << timeouts << "  \"coordinator\": {\"bind\": \"tcp://127.0.0.1:*\"},\n  \"workers\": [\n";
  for (std::size_t i = 0; i < endpoints.size(); ++i)
    f << "    {\"name\": \"w" << i << "\", \"address\": \"" << endpoints[i] << "\", \"data_bind\": \"tcp://127.0.0.1:*\"}"
      << (i + 1 < endpoints.size() ? ",\n" : "\n");
  f << "  ]\n}\n";
}

// Waits (a minute at most) until the run has written its results file's layout and first
// rows, then `more_ms`: the set-up takes long under the sanitizers and on a busy machine.
void wait_for_results(const fs::path& h5, int more_ms) {
  const auto start = Clock::now();
  while (!fs::exists(h5) && Clock::now() - start < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(more_ms));
}

}  // namespace

TEST_CASE("runs on 2, 3 and 4 processes write the one-process results bit for bit", "[apps][cluster]") {
  const fs::path d = scratch("cluster-identity");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 120 -o chain.json", dir).code == 0);
  REQUIRE(run("generate grid --rows 8 --cols 9 -o grid.json", dir).code == 0);
  REQUIRE(run("generate train --wagons 6 -o train.json", dir).code == 0);
  for (const std::string model : {"chain", "grid", "train"}) {
    // About 30 to 70 steps each (the train's stable step is far longer).
    const std::string common = "run " + model + ".json --t-end " + (model == "train" ? "0.5" : "0.05") + " --every 10 -q -o ";
    REQUIRE(run(common + model + "-1.h5 --threads 1 --partitions 1", dir).code == 0);
    for (int n : {2, 3, 4}) {
      const std::string out = model + "-" + std::to_string(n) + ".h5";
      const Result r = run(common + out + " --processes " + std::to_string(n) + (n == 3 ? " --transport ipc" : ""), dir);
      INFO(model << " on " << n << " processes: " << r.err);
      REQUIRE(r.code == 0);
      CHECK(same_results(d / (model + "-1.h5"), d / out));
    }
  }
  // DOPRI5: the workers take the same steps (one error norm over all of them) and write
  // the same dense output.
  const std::string dopri5 = "run chain.json --method dopri5 --rtol 1e-7 --t-end 0.05 --output-interval 0.005 -q -o ";
  REQUIRE(run(dopri5 + "chain-d1.h5 --threads 1 --partitions 1", dir).code == 0);
  const Result rd = run(dopri5 + "chain-d3.h5 --processes 3", dir);
  INFO(rd.err);
  REQUIRE(rd.code == 0);
  CHECK(same_results(d / "chain-d1.h5", d / "chain-d3.h5"));
  CHECK(mbsflow::ResultsFile((d / "chain-d3.h5").string()).time().size() == 11);
  // A cluster file with workers started by hand, two submodels on the first.
  Workers w(2, d);
  write_cluster(d / "cluster.json", w.endpoints);
  const Result r = run("run grid.json --t-end 0.05 --every 10 -q -o grid-c.h5 --cluster cluster.json --insecure --partitions 3", dir);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(same_results(d / "grid-1.h5", d / "grid-c.h5"));
  for (auto& p : w.procs) CHECK(p->wait(5.0) == std::optional<int>(0));
  fs::remove_all(d.parent_path());
}

TEST_CASE("rigid joints inside submodels: runs on 2 and 3 processes write the one-process results bit for bit",
          "[apps][cluster][rigid]") {
  const fs::path d = scratch("cluster-rigid");
  const std::string dir = d.string();
  {
    // Three double pendulums (rigid revolute pairs, one a velocity motor), tips tied by springs.
    std::ofstream f(d / "pendulums.json");
    f << R"({"name": "pendulums", "gravity": [0, -9.81, 0], "bodies": [)";
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 2; ++r)
        f << (c + r ? ", " : "") << R"({"name": "p)" << c << r << R"(", "mass": 1, "inertia": [0.001, 0.08, 0.08], "position": [)"
          << 0.5 + r << ", 0, " << 0.5 * c << "]}";
    f << R"(], "joints": [)";
    for (int c = 0; c < 3; ++c) {
      f << (c ? ", " : "") << R"({"type": "revolute", "body1": "ground", "body2": "p)" << c << R"(0", "point1": [0, 0, )" << 0.5 * c
        << R"(], "point2": [-0.5, 0, 0])" << (c == 1 ? R"(, "motor": {"type": "velocity", "function": {"type": "constant", "value": 1}})" : "")
        << R"(}, {"type": "revolute", "body1": "p)" << c << R"(0", "body2": "p)" << c << R"(1", "point1": [0.5, 0, 0], "point2": [-0.5, 0, 0]})";
      if (c) f << R"(, {"type": "spring", "body1": "p)" << c - 1 << R"(1", "body2": "p)" << c << R"(1", "point1": [0.5, 0, 0], "point2": [0.5, 0, 0], "stiffness": 200, "damping": 1})";
    }
    f << R"(], "simulation": {"t_end": 0.2, "step": 0.002, "output_every": 10}})";
  }
  const std::string common = "run pendulums.json -q --fields all -o ";
  REQUIRE(run(common + "p1.h5 --threads 1 --partitions 1", dir).code == 0);
  for (int n : {2, 3}) {
    const std::string out = "p" + std::to_string(n) + ".h5";
    const Result r = run(common + out + " --processes " + std::to_string(n), dir);
    INFO(n << " processes: " << r.err);
    REQUIRE(r.code == 0);
    CHECK(same_results(d / "p1.h5", d / out));
    const mbsflow::ResultsFile a((d / "p1.h5").string()), b((d / out).string());
    CHECK(a.read("/joints/force") == b.read("/joints/force"));
    CHECK(a.read("/joints/motor_effort") == b.read("/joints/motor_effort"));
  }
  const Result four = run(common + "p4.h5 --processes 4", dir);
  CHECK(four.code == 2);
  CHECK_THAT(four.err, Catch::Contains("rigid joints leave only 3 pieces"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("a worker killed mid-run: the coordinator names it, keeps the results and exits 1 within 5 s",
          "[apps][cluster][faults]") {
  for (const bool loose : {false, true}) {
    INFO((loose ? "loose" : "tight") << " coupling");
    const fs::path d = scratch(loose ? "cluster-worker-lost-loose" : "cluster-worker-lost");
    const std::string dir = d.string();
    REQUIRE(run("generate chain --bodies 400 -o chain.json", dir).code == 0);
    Workers w(2, d);
    write_cluster(d / "cluster.json", w.endpoints);
    std::vector<std::string> args{"run", "chain.json", "--cluster", "cluster.json", "--insecure", "--t-end", "1000", "--every", "20", "-o", "out.h5"};
    if (loose) args.insert(args.end(), {"--coupling", "loose"});
    Child coordinator(args, d, "coordinator");
    wait_for_results(d / "out.h5", 1500);
    REQUIRE(!coordinator.wait(0.0));
    w.procs[1]->kill(SIGKILL);
    const auto killed = Clock::now();
    const std::optional<int> code = coordinator.wait(10.0);
    const double took = std::chrono::duration<double>(Clock::now() - killed).count();
    const std::string err = coordinator.err();
    INFO(err);
    CHECK(code == std::optional<int>(1));
    CHECK(took < 5.0);
    CHECK(err.find("worker w1 (" + w.endpoints[1] + ", submodels 1) was lost") != std::string::npos);
    CHECK(err.find("every worker had completed t = ") != std::string::npos);
    // The results file holds the snapshots the message counts.
    const std::size_t at = err.find("results keep ");
    REQUIRE(at != std::string::npos);
    const long kept = std::stol(err.substr(at + 13));
    CHECK(kept > 1);
    const mbsflow::ResultsFile results((d / "out.h5").string());
    CHECK(static_cast<long>(results.time().size()) == kept);
    // The other worker was told to stop and leaves nothing behind.
    CHECK(w.procs[0]->wait(5.0) == std::optional<int>(1));
    CHECK(w.procs[0]->err().find("stopped by the coordinator") != std::string::npos);
  }
  fs::remove_all(scratch("").parent_path());
}

TEST_CASE("a stopped (SIGSTOP) or hung worker is named and the run stopped like a killed one", "[apps][cluster][faults]") {
  for (const std::string fault : {"SIGSTOP", "hung step"}) {
    INFO(fault);
    const fs::path d = scratch(fault == "SIGSTOP" ? "cluster-worker-stopped" : "cluster-worker-hung");
    const std::string dir = d.string();
    REQUIRE(run("generate chain --bodies 400 -o chain.json", dir).code == 0);
    Workers w0(1, d, {}, "first");
    // The second one's step never ends 3 s into the run (a test hook), while its I/O
    // thread goes on sending heartbeats.
    Workers w1(1, d, fault == "SIGSTOP" ? std::vector<std::string>{} : std::vector<std::string>{"--test-hang-after", "3"}, "second");
    write_cluster(d / "cluster.json", {w0.endpoints[0], w1.endpoints[0]},
                  "  \"timeouts\": {\"heartbeat_s\": 0.5, \"lost_s\": 3, \"stall_s\": 2},\n");
    Child coordinator({"run", "chain.json", "--cluster", "cluster.json", "--insecure", "--t-end", "1000", "--every", "20", "-o", "out.h5"},
                      d, "coordinator");
    wait_for_results(d / "out.h5", 1500);
    REQUIRE(!coordinator.wait(0.0));
    if (fault == "SIGSTOP") w1.procs[0]->kill(SIGSTOP);
    const auto from = Clock::now();
    const std::optional<int> code = coordinator.wait(15.0);
    const double took = std::chrono::duration<double>(Clock::now() - from).count();
    const std::string err = coordinator.err();
    INFO(err);
    CHECK(code == std::optional<int>(1));
    // lost_s (3 s) after the stop; stall_s (2 s) after the hang, which begins 0 to 1 s from here.
    CHECK(took < (fault == "SIGSTOP" ? 5.0 : 6.0));
    CHECK(err.find("worker w1 (" + w1.endpoints[0] + ", submodels 1) " + (fault == "SIGSTOP" ? "was lost" : "is hung")) !=
          std::string::npos);
    const std::size_t at = err.find("results keep ");
    REQUIRE(at != std::string::npos);
    CHECK(static_cast<long>(mbsflow::ResultsFile((d / "out.h5").string()).time().size()) == std::stol(err.substr(at + 13)));
    CHECK(w0.procs[0]->wait(5.0) == std::optional<int>(1));
    if (fault == "SIGSTOP") w1.procs[0]->kill(SIGCONT);
    CHECK(w1.procs[0]->wait(10.0).has_value());  // told to stop, or lost its coordinator
  }
  fs::remove_all(scratch("").parent_path());
}

TEST_CASE("a stopped worker of --processes ends the run within 5 s of its last sign of life", "[apps][cluster][faults]") {
  const fs::path d = scratch("processes-worker-stopped");
  REQUIRE(run("generate chain --bodies 400 -o chain.json", d.string()).code == 0);
  Child coordinator({"run", "chain.json", "--processes", "2", "--t-end", "1000", "--every", "20", "-o", "out.h5"}, d,
                    "coordinator");
  wait_for_results(d / "out.h5", 1500);
  REQUIRE(!coordinator.wait(0.0));
  // Its workers are its children (the /proc task list of its threads).
  std::vector<pid_t> workers;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(coordinator.pid()) + "/task")) {
    std::ifstream in(task.path() / "children");
    for (pid_t p; in >> p;) workers.push_back(p);
  }
  REQUIRE(workers.size() == 2);
  ::kill(workers[1], SIGSTOP);
  const auto from = Clock::now();
  const std::optional<int> code = coordinator.wait(15.0);
  const double took = std::chrono::duration<double>(Clock::now() - from).count();
  INFO(coordinator.err());
  CHECK(code == std::optional<int>(1));
  CHECK(coordinator.err().find("was lost") != std::string::npos);
  CHECK(took < 5.0);  // lost_s (3 s) after the stop, and the stopped worker killed rather than waited for
  for (pid_t p : workers) CHECK(::kill(p, 0) != 0);  // none left behind
  fs::remove_all(scratch("").parent_path());
}

TEST_CASE("the coordinator killed: every worker notices and exits within 5 s", "[apps][cluster][faults]") {
  const fs::path d = scratch("cluster-coordinator-lost");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 2000 -o chain.json", dir).code == 0);
  Workers w(3, d);
  write_cluster(d / "cluster.json", w.endpoints);
  Child coordinator({"run", "chain.json", "--cluster", "cluster.json", "--insecure", "--t-end", "1000", "-o", "out.h5"}, d, "coordinator");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  REQUIRE(!coordinator.wait(0.0));
  coordinator.kill(SIGKILL);
  const auto killed = Clock::now();
  for (auto& p : w.procs) {
    const std::optional<int> code = p->wait(10.0);
    INFO(p->err());
    CHECK(code == std::optional<int>(1));
    CHECK(p->err().find("the coordinator was lost") != std::string::npos);
  }
  CHECK(std::chrono::duration<double>(Clock::now() - killed).count() < 5.0);
  // --processes: the local workers go with a killed coordinator too (they are its children).
  Child local({"run", "chain.json", "--processes", "2", "--t-end", "1000", "-q"}, d, "local");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  REQUIRE(!local.wait(0.0));
  const std::string children = "/proc/" + std::to_string(local.pid()) + "/task/" + std::to_string(local.pid()) + "/children";
  const std::string pids = read_text(children);
  CHECK(!pids.empty());
  local.kill(SIGKILL);
  REQUIRE(local.wait(5.0));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Gone, or a zombie waiting for an init that does not reap (as in some containers).
  std::istringstream list(pids);
  for (long pid; list >> pid;) {
    const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
    INFO(stat);
    CHECK((stat.empty() || stat.find(") Z ") != std::string::npos));
  }
  fs::remove_all(d.parent_path());
}

TEST_CASE("cluster set-up errors: unreachable worker, port in use, bad cluster file, version mismatch",
          "[apps][cluster][faults]") {
  const fs::path d = scratch("cluster-errors");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 50 -o chain.json", dir).code == 0);

  // Nothing listens at the worker's address.
  write_cluster(d / "nobody.json", {"tcp://127.0.0.1:1"}, "  \"timeouts\": {\"connect_s\": 1},\n");
  const auto start = Clock::now();
  const Result unreachable = run("run chain.json --t-end 0.01 --cluster nobody.json --insecure", dir);
  CHECK(unreachable.code == 1);
  CHECK(unreachable.err.find("worker w0 (tcp://127.0.0.1:1, submodels 0) did not answer within 1 s") != std::string::npos);
  CHECK(std::chrono::duration<double>(Clock::now() - start).count() < 5.0);

  // The implicit methods integrate whole models, not submodels whose stages are exchanged.
  const Result colloc = run("run chain.json --processes 2 --method colloc", dir);
  CHECK(colloc.code == 2);
  CHECK(colloc.err.find("a tightly coupled run of several submodels exchanges RK4 or DOPRI5 stages; colloc") !=
        std::string::npos);

  // A second worker on a port that is taken.
  Workers first(1, d);
  Child second({"worker", "--listen", first.endpoints[0], "--insecure"}, d, "second");
  CHECK(second.wait(5.0) == std::optional<int>(2));
  CHECK(second.err().find("cannot bind the worker's control socket at " + first.endpoints[0] + ": Address already in use") !=
        std::string::npos);

  // A malformed cluster file.
  std::ofstream(d / "bad.json") << "{\n  \"transport\": \"tcp\",\n  \"workers\": [\n    {\"address\": 5}\n  ]\n}\n";
  const Result bad = run("run chain.json --cluster bad.json --insecure", dir);
  CHECK(bad.code == 2);
  CHECK(bad.err.find("bad.json:1:1: missing field 'coordinator'") != std::string::npos);
  std::ofstream(d / "broken.json") << "{\n  \"transport\": \"tcp\",\n";
  const Result broken = run("run chain.json --cluster broken.json --insecure", dir);
  CHECK(broken.code == 2);
  CHECK(broken.err.find("broken.json:3:1: invalid JSON") != std::string::npos);

  // A worker of another protocol version: the coordinator says so and both exit 1.
  Workers other(1, d, {"--protocol-version", "999"}, "other");
  write_cluster(d / "other.json", other.endpoints);
  const Result mismatch = run("run chain.json --t-end 0.01 --cluster other.json --insecure", dir);
  CHECK(mismatch.code == 1);
  CHECK(mismatch.err.find("version mismatch: coordinator runs mbsflow") != std::string::npos);
  CHECK(mismatch.err.find("(protocol 999)") != std::string::npos);
  CHECK(other.procs[0]->wait(5.0) == std::optional<int>(1));
  // The first worker was never used; it goes when told to (SIGTERM).
  first.procs[0]->kill(SIGTERM);
  CHECK(first.procs[0]->wait(5.0).has_value());
  fs::remove_all(d.parent_path());
}

TEST_CASE("Ctrl-C on the coordinator stops its workers and keeps the results", "[apps][cluster][faults]") {
  const fs::path d = scratch("cluster-interrupt");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 400 -o chain.json", dir).code == 0);
  Child coordinator({"run", "chain.json", "--processes", "2", "--t-end", "1000", "--every", "20", "-o", "out.h5"}, d,
                    "coordinator");
  wait_for_results(d / "out.h5", 1500);
  REQUIRE(!coordinator.wait(0.0));
  const std::string children =
      read_text("/proc/" + std::to_string(coordinator.pid()) + "/task/" + std::to_string(coordinator.pid()) + "/children");
  CHECK(!children.empty());
  coordinator.kill(SIGINT);
  const std::optional<int> code = coordinator.wait(5.0);
  const std::string err = coordinator.err();
  INFO(err);
  CHECK(code == std::optional<int>(1));
  CHECK(err.find("interrupted at t = ") != std::string::npos);
  CHECK(err.find("(SIGINT) in out.h5") != std::string::npos);
  const std::size_t at = err.find("results keep ");
  REQUIRE(at != std::string::npos);
  CHECK(static_cast<long>(mbsflow::ResultsFile((d / "out.h5").string()).time().size()) == std::stol(err.substr(at + 13)));
  std::istringstream list(children);
  for (long pid; list >> pid;) {
    const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
    CHECK((stat.empty() || stat.find(") Z ") != std::string::npos));
  }
  fs::remove_all(d.parent_path());
}
