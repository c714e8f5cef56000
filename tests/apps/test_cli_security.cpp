// Authenticated runs across processes (ZeroMQ CURVE with a ZAP handler): keys made with
// `mbsflow keygen`, named in the cluster file; a coordinator or worker whose key is not
// listed, or that has none, is refused and logged, and nothing is written.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <fstream>

#include "process_support.hpp"

using namespace mbsflow::test;

namespace {

std::string keygen(const fs::path& dir, const std::string& name) {
  const Result r = run("keygen " + name, dir.string(), true);
  REQUIRE(r.code == 0);
  return trim(r.out);
}

// The keys every process admits (what a worker reads of the cluster file) and the full
// cluster file of the coordinator, once the workers' endpoints are known.
void write_keys(const fs::path& file, const std::string& coordinator, const std::vector<std::string>& workers) {
  std::ofstream f(file);
  f << "{\"coordinator\": {\"public_key\": \"" << coordinator << "\"}, \"workers\": [";
  for (std::size_t i = 0; i < workers.size(); ++i) f << (i ? ", " : "") << "{\"public_key\": \"" << workers[i] << "\"}";
  f << "]}\n";
}

void write_cluster(const fs::path& file, const std::string& secret, const std::string& coordinator,
                   const std::vector<std::string>& endpoints, const std::vector<std::string>& keys) {
  std::ofstream f(file);
  f << "{\"secret_key\": \"" << secret << "\", \"timeouts\": {\"connect_s\": 3},\n"
    << " \"coordinator\": {\"bind\": \"tcp://127.0.0.1:*\", \"public_key\": \"" << coordinator << "\"},\n \"workers\": [";
  for (std::size_t i = 0; i < endpoints.size(); ++i)
    f << (i ? ", " : "") << "{\"name\": \"w" << i << "\", \"address\": \"" << endpoints[i]
      << "\", \"data_bind\": \"tcp://127.0.0.1:*\", \"public_key\": \"" << keys[i] << "\"}";
  f << "]}\n";
}

struct KeyedWorkers {
  std::vector<std::unique_ptr<Child>> procs;
  std::vector<std::string> endpoints;
  // tag: names the processes' output files, new for every set (a file of an earlier set
  // could be read before the new process has truncated it).
  KeyedWorkers(const fs::path& d, int n, const std::string& tag) {
    for (int i = 0; i < n; ++i) {
      procs.push_back(std::make_unique<Child>(std::vector<std::string>{"worker", "--listen", "tcp://127.0.0.1:*", "--threads", "1",
                                                                        "--cluster", "keys.json", "--key", "w" + std::to_string(i) + ".key"},
                                              d, tag + std::to_string(i)));
      endpoints.push_back(procs.back()->endpoint());
      REQUIRE(!endpoints.back().empty());
    }
  }
};

}  // namespace

TEST_CASE("keygen writes an owner-only secret key and never overwrites one", "[apps][security]") {
  const fs::path d = scratch("keygen");
  const std::string pub = keygen(d, "host");
  CHECK(pub.size() == 40);
  struct stat st {};
  REQUIRE(::stat((d / "host.key").c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0600);
  CHECK(read_text(d / "host.pub").find(pub) != std::string::npos);
  const Result again = run("keygen host", d.string());
  CHECK(again.code == 2);
  CHECK_THAT(again.err, Catch::Contains("host.key: File exists (a key is never overwritten)"));
  ::chmod((d / "host.key").c_str(), 0644);
  std::ofstream(d / "c.json") << "{\"secret_key\": \"host.key\", \"coordinator\": {\"bind\": \"tcp://127.0.0.1:*\"}, "
                                 "\"workers\": [{\"address\": \"tcp://127.0.0.1:1\", \"data_bind\": \"tcp://127.0.0.1:*\"}]}";
  REQUIRE(run("generate chain --bodies 4 -o chain.json", d.string()).code == 0);
  const Result open_key = run("run chain.json --cluster c.json", d.string());
  CHECK(open_key.code == 2);
  CHECK_THAT(open_key.err, Catch::Contains("readable by others"));
  fs::remove_all(d.parent_path());
}

TEST_CASE("a keyed run is the insecure run bit for bit, and a wrong or missing key is refused, logged, nothing written",
          "[apps][security][cluster]") {
  const fs::path d = scratch("curve");
  const std::string dir = d.string();
  REQUIRE(run("generate chain --bodies 40 -o chain.json", dir).code == 0);
  const std::string kc = keygen(d, "coordinator"), k0 = keygen(d, "w0"), k1 = keygen(d, "w1"), intruder = keygen(d, "intruder");
  write_keys(d / "keys.json", kc, {k0, k1});
  const std::string common = "run chain.json --t-end 0.02 --every 10 -q ";

  {  // the keyed run
    KeyedWorkers w(d, 2, "keyed");
    write_cluster(d / "cluster.json", "coordinator.key", kc, w.endpoints, {k0, k1});
    const Result r = run(common + "--cluster cluster.json -o keyed.h5", dir);
    INFO(r.err);
    CHECK(r.code == 0);
    for (auto& p : w.procs) CHECK(p->wait(10.0) == std::optional<int>(0));
  }
  REQUIRE(run(common + "--processes 2 -o local.h5", dir).code == 0);  // keys made for the run
  REQUIRE(run(common + "--partitions 2 -o one.h5", dir).code == 0);
  CHECK(std::system(("h5diff -q '" + dir + "/keyed.h5' '" + dir + "/one.h5' /bodies /bodies").c_str()) == 0);
  CHECK(std::system(("h5diff -q '" + dir + "/local.h5' '" + dir + "/one.h5' /bodies /bodies").c_str()) == 0);

  {  // a coordinator with a key the workers do not list
    KeyedWorkers w(d, 2, "refusing");
    write_cluster(d / "intruder.json", "intruder.key", intruder, w.endpoints, {k0, k1});
    const Result r = run(common + "--cluster intruder.json -o intruder.h5", dir);
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("did not answer within 3 s"));
    CHECK_FALSE(fs::exists(d / "intruder.h5"));
    CHECK_THAT(r.err, Catch::Contains("no results file was written"));
    for (int i = 0; i < 100 && w.procs[0]->err().find("refused") == std::string::npos; ++i)  // logged on its I/O thread
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    CHECK_THAT(w.procs[0]->err(), Catch::Contains("refused a CURVE client") && Catch::Contains("key " + intruder));
  }
  {  // a coordinator without keys at keyed workers
    KeyedWorkers w(d, 1, "plain");
    std::ofstream(d / "plain.json") << "{\"timeouts\": {\"connect_s\": 3}, \"coordinator\": {\"bind\": \"tcp://127.0.0.1:*\"}, "
                                       "\"workers\": [{\"address\": \"" << w.endpoints[0] << "\", \"data_bind\": \"tcp://127.0.0.1:*\"}]}";
    const Result no_keys = run(common + "--cluster plain.json -o plain.h5", dir);
    CHECK(no_keys.code == 2);  // refused before it starts: keys or --insecure
    CHECK_THAT(no_keys.err, Catch::Contains("the cluster file gives no keys"));
    const Result insecure = run(common + "--cluster plain.json --insecure -o plain.h5", dir);
    CHECK(insecure.code == 1);  // the keyed worker does not answer a coordinator without a key
    CHECK_FALSE(fs::exists(d / "plain.h5"));
  }
  // Insecure is for loopback unless asked for anywhere.
  const Result open_worker = run("worker --listen tcp://0.0.0.0:* --insecure --idle-timeout 1", dir);
  CHECK(open_worker.code == 2);
  CHECK_THAT(open_worker.err, Catch::Contains("is not a loopback endpoint"));
  const Result no_key_worker = run("worker --listen tcp://127.0.0.1:* --idle-timeout 1", dir);
  CHECK(no_key_worker.code == 2);
  CHECK_THAT(no_key_worker.err, Catch::Contains("no key"));
  fs::remove_all(d.parent_path());
}
