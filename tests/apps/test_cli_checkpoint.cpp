// mbsflow run --checkpoint-every / --resume: kill -9 at random moments, resume, and the
// results file holds bit for bit what the uninterrupted run wrote (h5diff, a real
// reader); damaged checkpoints and misuse are refused with a message.
#include <catch2/catch.hpp>
#include <random>
#include <thread>

#include "process_support.hpp"
#include "../io/superblock_edit.hpp"

using namespace mbsflow::test;

namespace {

// h5diff's exit code for two results files, their datasets compared (the attributes
// differ: the command line, the run id).
int h5diff(const fs::path& a, const fs::path& b) {
  const std::string cmd = "h5diff --exclude-attribute / '" + a.string() + "' '" + b.string() + "' > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool wait_for_file(const fs::path& p, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!fs::exists(p)) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace

TEST_CASE("kill -9 at random moments then resume: the results file is bit for bit the uninterrupted run's", "[apps][checkpoint]") {
  const fs::path d = scratch("checkpoint_kill9");
  REQUIRE(run("generate chain --bodies 1000 -o chain.json", d.string()).code == 0);
  REQUIRE(run("generate chain --bodies 60 -o short.json", d.string()).code == 0);
  const unsigned seed = std::random_device{}();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  int killed = 0, tries = 0;
  struct Case {
    std::string model, t_end, method, threads;
    std::vector<std::string> more;
  };
  // RK4 and DOPRI5 with the whole model in one stepper (1 thread) and cut into submodels
  // (2); the implicit methods (whole) on a shorter chain, each run a second or two;
  // loosely coupled, with a fixed and with an adaptive macro step; on worker processes.
  const std::vector<Case> cases{
      {"chain.json", "2", "rk4", "1", {}},
      {"chain.json", "2", "rk4", "2", {}},
      {"chain.json", "2", "dopri5", "1", {}},
      {"chain.json", "2", "dopri5", "2", {}},
      {"short.json", "1", "colloc", "1", {}},
      {"short.json", "2", "tirk", "2", {}},
      {"chain.json", "2", "rk4", "2", {"--coupling", "loose", "--partitions", "3", "--submodel-methods", "rk4,dopri5,rk4"}},
      {"chain.json", "2", "rk4", "1", {"--processes", "2"}},
      {"chain.json", "2", "dopri5", "1", {"--processes", "2", "--partitions", "3"}},
      {"chain.json", "2", "rk4", "1", {"--processes", "2", "--coupling", "loose", "--submodel-methods", "rk4,dopri5"}},
      {"chain.json", "2", "rk4", "2", {"--coupling", "loose", "--partitions", "2", "--coupling-tol", "1e-9"}}};
  for (const Case& c : cases) {
    std::vector<std::string> args{"run", c.model, "--t-end", c.t_end, "--output-interval", "0.02", "--method",
                                  c.method, "--threads", c.threads, "-q"};
    args.insert(args.end(), c.more.begin(), c.more.end());
    std::string line;
    for (std::size_t i = 1; i < args.size(); ++i) line += args[i] + " ";
    REQUIRE(run("run " + line + "-o ref.h5", d.string()).code == 0);
    for (int k = 0; k < 2; ++k, ++tries) {
      INFO(line << "try " << k);
      fs::remove(d / "a.h5");
      fs::remove(d / "a.h5.ckpt");
      std::vector<std::string> with = args;
      with.insert(with.end(), {"-o", "a.h5", "--checkpoint-every", "0.05"});
      Child child(with, d, "child");
      REQUIRE(wait_for_file(d / "a.h5.ckpt", 60.0));
      std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 500)(rng)));
      child.kill(SIGKILL);
      const std::optional<int> code = child.wait(30.0);
      REQUIRE(code);
      if (*code == -SIGKILL) ++killed;
      const Result resumed = run("run --resume a.h5.ckpt", d.string());
      INFO(resumed.err);
      REQUIRE(resumed.code == 0);
      CHECK_THAT(resumed.err, Catch::Contains("went on from the checkpoint at t = "));
      CHECK(h5diff(d / "ref.h5", d / "a.h5") == 0);
    }
  }
  CHECK(killed >= tries / 2);  // most runs were really killed half-way, not already done
  fs::remove_all(d.parent_path());
}

TEST_CASE("a run killed as it closed its results file, before the file reached its recorded end, resumes", "[apps][checkpoint]") {
  // What one kill in 65 left (a 1000-body chain, killed in the results file's last close):
  // the superblock records an end 415 bytes past the file's, which HDF5 refuses to open.
  const fs::path d = scratch("checkpoint_killed_in_close");
  REQUIRE(run("generate chain --bodies 50 -o chain.json", d.string()).code == 0);
  REQUIRE(run("run chain.json --t-end 0.2 -q -o ref.h5", d.string()).code == 0);
  REQUIRE(run("run chain.json --t-end 0.2 -q -o a.h5 --checkpoint-every 1e-6", d.string()).code == 0);
  const std::string a = (d / "a.h5").string();
  rewrite_superblock(a, 1, fs::file_size(a) + 415);
  CHECK(std::system(("h5ls '" + a + "' > /dev/null 2>&1").c_str()) != 0);  // HDF5 refuses it as it is
  const Result resumed = run("run --resume a.h5.ckpt", d.string());
  INFO(resumed.err);
  CHECK(resumed.code == 0);
  CHECK_THAT(resumed.err, Catch::Contains("went on from the checkpoint at t = "));
  CHECK(h5diff(d / "ref.h5", d / "a.h5") == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("damaged checkpoints, replaced results files and misuse are refused with a message", "[apps][checkpoint]") {
  const fs::path d = scratch("checkpoint_refusals");
  REQUIRE(run("generate chain --bodies 200 -o chain.json", d.string()).code == 0);
  // A checkpoint at every step (wall clock 1 us): the last one is of the run's last steps.
  REQUIRE(run("run chain.json --t-end 0.2 -q -o a.h5 --checkpoint-every 1e-6", d.string()).code == 0);
  const std::string good = read_text(d / "a.h5.ckpt");
  REQUIRE(good.size() > 100);
  auto write = [&](const std::string& text) { std::ofstream(d / "bad.ckpt", std::ios::binary) << text; };

  write(good.substr(0, good.size() - 20));  // torn: a write cut short
  CHECK_THAT(run("run --resume bad.ckpt", d.string()).err, Catch::Contains("is cut short"));
  std::string flipped = good;
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x10);
  write(flipped);
  const Result damaged = run("run --resume bad.ckpt", d.string());
  CHECK(damaged.code == 2);
  CHECK_THAT(damaged.err, Catch::Contains("is damaged: its checksum does not match"));
  write("{\"bodies\": [], \"joints\": [], \"simulation\": {\"t_end\": 1}}");
  CHECK_THAT(run("run --resume bad.ckpt", d.string()).err, Catch::Contains("is not an mbsflow checkpoint"));
  CHECK_THAT(run("run --resume missing.ckpt", d.string()).err, Catch::Contains("cannot read the checkpoint"));

  // Another run wrote the results file since: the checkpoint does not belong to it.
  REQUIRE(run("run chain.json --t-end 0.2 -q -o a.h5", d.string()).code == 0);
  const Result other = run("run --resume a.h5.ckpt", d.string());
  CHECK(other.code == 2);
  CHECK_THAT(other.err, Catch::Contains("is not the results file of the run this checkpoint was taken from"));
  fs::remove(d / "a.h5");
  CHECK_THAT(run("run --resume a.h5.ckpt", d.string()).err, Catch::Contains("the results file a.h5 is gone"));

  CHECK_THAT(run("run --resume a.h5.ckpt --t-end 5", d.string()).err, Catch::Contains("give no --t-end"));
  CHECK_THAT(run("run", d.string()).err, Catch::Contains("give a MODEL file, or --resume CHECKPOINT"));
  CHECK_THAT(run("run chain.json --checkpoint-every 1", d.string()).err, Catch::Contains("give -o FILE"));
  fs::remove_all(d.parent_path());
}
