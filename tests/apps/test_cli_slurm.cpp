// mbsflow run --slurm, tested as Slurm would start it: one process per task with the
// step's variables set, every task on a loopback address (127.0.0.1 and 127.0.0.2 stand
// for two nodes), started and stopped by the test.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <catch2/catch.hpp>
#include <memory>

#include "cli_support.hpp"
#include "process_support.hpp"

using namespace mbsflow::test;

namespace {

bool can_bind(const char* address, int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  ::inet_pton(AF_INET, address, &a.sin_addr);
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

// A base port whose next `count` ports are free on both loopback addresses just now.
int free_ports(int count) {
  for (int base = 30000 + 97 * (::getpid() % 200); base < 65000; base += count) {
    bool free = true;
    for (int p = base; p < base + count && free; ++p) free = can_bind("127.0.0.1", p) && can_bind("127.0.0.2", p);
    if (free) return base;
  }
  FAIL("no free ports");
  return 0;
}

// The tasks of one step, each `mbsflow ARGS` with the step's variables.
std::vector<std::unique_ptr<Child>> start_step(const fs::path& d, const std::vector<std::string>& args,
                                               const std::vector<std::string>& step_vars, int tasks) {
  std::vector<std::unique_ptr<Child>> t;
  for (int r = 0; r < tasks; ++r) {
    std::vector<std::string> env = step_vars;
    env.push_back("SLURM_PROCID=" + std::to_string(r));
    env.push_back("SLURM_NTASKS=" + std::to_string(tasks));
    env.push_back("HOME=" + (d / "home").string());
    t.push_back(std::make_unique<Child>(args, d, "task" + std::to_string(r), env));
  }
  return t;
}

}  // namespace

TEST_CASE("srun of 3 tasks on two nodes: task 0 writes the one-process results bit for bit", "[apps][cluster][slurm]") {
  const fs::path d = scratch("slurm-identity");
  const std::string dir = d.string();
  fs::create_directories(d / "home/.mbsflow");
  REQUIRE(run("keygen home/.mbsflow/cluster", dir).code == 0);
  REQUIRE(run("generate grid --rows 8 --cols 9 -o grid.json", dir).code == 0);
  const std::string common = " --t-end 0.05 --every 10 -q -o ";
  REQUIRE(run("run grid.json" + common + "one.h5 --threads 1 --partitions 1", dir).code == 0);
  // Cyclic: task 0 and task 2 on the first node, task 1 on the second.
  const int port = free_ports(4);
  auto tasks = start_step(d, {"run", "grid.json", "--slurm", "--slurm-port", std::to_string(port), "--threads", "1",
                              "--t-end", "0.05", "--every", "10", "-o", "slurm.h5"},
                          {"SLURM_STEP_NODELIST=127.0.0.[1-2]", "SLURM_STEP_TASKS_PER_NODE=2,1",
                           "SLURM_DISTRIBUTION=cyclic", "SLURM_JOB_ID=99"},
                          3);
  for (auto& t : tasks) {
    INFO(t->err());
    CHECK(t->wait(60.0) == std::optional<int>(0));
  }
  CHECK(tasks[1]->endpoint() == "tcp://127.0.0.2:" + std::to_string(port));
  CHECK(tasks[2]->endpoint() == "tcp://127.0.0.1:" + std::to_string(port + 2));
  CHECK_THAT(tasks[0]->err(), Catch::Contains("2 submodels on 2 worker processes"));
  CHECK(same_results(d / "one.h5", d / "slurm.h5"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("run --slurm: no key pair in the shared home and one task", "[apps][slurm]") {
  const fs::path d = scratch("slurm-setup");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 20 -o chain.json", dir).code == 0);
  const std::vector<std::string> args{"run", "chain.json", "--slurm", "--t-end", "0.01", "-o", "r.h5"};
  const std::vector<std::string> step{"SLURM_STEP_NODELIST=127.0.0.1", "SLURM_JOB_ID=1"};
  {
    auto tasks = start_step(d, args, step, 2);
    for (auto& t : tasks) {
      CHECK(t->wait(30.0) == std::optional<int>(2));
      CHECK_THAT(t->err(), Catch::Contains("no key pair at " + (d / "home/.mbsflow/cluster.key").string()) &&
                               Catch::Contains("mbsflow keygen"));
    }
  }
  fs::create_directories(d / "home/.mbsflow");
  REQUIRE(run("keygen home/.mbsflow/cluster", dir).code == 0);
  auto one = start_step(d, args, step, 1);
  CHECK(one[0]->wait(60.0) == std::optional<int>(0));
  CHECK_THAT(one[0]->err(), Catch::Contains("one task: a run on this process's threads"));
  CHECK(fs::exists(d / "r.h5"));
  // Outside srun the variables are missing, and the message says so.
  const Result r = run("run chain.json --slurm --t-end 0.01", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("SLURM_NTASKS is not set (start the run with srun)"));
  fs::remove_all(d.parent_path());
}
