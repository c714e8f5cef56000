// Messages from whoever reaches a port (the findings of issue 21, replayed): a worker and
// a run survive them, and the results are those of an undisturbed run, bit for bit.
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <zmq.hpp>

#include "cluster_wire.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "thread_workers.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

zmq::message_t ask(zmq::socket_t& s, const std::string& text) {
  s.send(zmq::buffer(text), zmq::send_flags::none);
  zmq::message_t reply;
  s.set(zmq::sockopt::rcvtimeo, 500);
  (void)s.recv(reply);
  return reply;
}

// The old (version 1) result header: a done without any run id.
struct OldResultHeader {
  std::uint32_t magic = wire::magic;
  wire::ResultKind kind = wire::ResultKind::done;
  std::int32_t worker = 0, pad = 0;
  std::int64_t step = 1, index = 0;
  double t = 0.0;
};

Model chain_run(int bodies, int steps) {
  ChainParams chain;
  chain.bodies = bodies;
  return short_run(make_chain(chain), steps);
}

test::MemorySink one_process(const Model& m) {
  MultibodySystem sys(m);
  test::MemorySink reference;
  run_simulation(sys, options_from_model(m), &reference);
  return reference;
}

}  // namespace

TEST_CASE("a worker drops malformed control messages and refuses a hello that would hold it forever",
          "[runtime][cluster][wire]") {
  const Model m = chain_run(12, 30);
  const RunOptions o = options_from_model(m);
  const test::MemorySink reference = one_process(m);

  ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
  zmq::context_t ctx;
  zmq::socket_t attacker(ctx, zmq::socket_type::dealer);
  attacker.set(zmq::sockopt::linger, 0);
  attacker.connect(pool.endpoints[0]);
  // Each of these had aborted the worker (an exception on its I/O thread) or held it.
  for (const std::string& frame : std::vector<std::string>{R"({"type":5})", "not json", "[1,2,3]", R"({"type":"setup","model":7})",
                                  std::string(100, '[') + std::string(100, ']')})
    CHECK(ask(attacker, frame).size() == 0);  // dropped, unanswered
  const zmq::message_t refused = ask(
      attacker, R"({"type":"hello","run":"0123456789abcdef","timeouts":{"connect_s":10,"heartbeat_s":0.5,"lost_s":1e300}})");
  CHECK_THAT(refused.to_string(), Catch::Contains("refused a hello"));
  CHECK(ask(attacker, R"({"type":"hello","timeouts":{"connect_s":10,"heartbeat_s":0.5,"lost_s":3}})").to_string().find(
            "refused a hello") != std::string::npos);  // no run id

  // The workers still serve a run, and it is the undisturbed one.
  ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
  for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
  const Decomposition d = decompose(m, cluster_submodels(c));
  test::MemorySink sink;
  run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr);
  REQUIRE(sink.states.size() == reference.states.size());
  CHECK(sink.states.back() == reference.states.back());
  for (const std::string& e : pool.errors) CHECK(e.empty());
}

TEST_CASE("stray and forged frames at the data and results inboxes neither stop nor end a run",
          "[runtime][cluster][wire]") {
  const Model m = chain_run(24, 600);
  const RunOptions o = options_from_model(m);
  const test::MemorySink reference = one_process(m);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("mbsflow_wire_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  ThreadWorkers pool({"ipc://" + (dir / "ctl0").string(), "ipc://" + (dir / "ctl1").string()});
  const ClusterConfig c = cluster_of(pool.endpoints, "ipc://" + (dir / "data").string(), "ipc://" + (dir / "results").string());
  const Decomposition d = decompose(m, cluster_submodels(c));

  std::atomic<bool> over{false};
  std::atomic<long> sent{0};
  std::thread attacker([&] {
    zmq::context_t ctx;
    std::vector<zmq::socket_t> to;
    for (const std::string& e : {c.results_bind, c.workers[0].data_bind, c.workers[1].data_bind}) {
      to.emplace_back(ctx, zmq::socket_type::push);
      to.back().set(zmq::sockopt::linger, 0);
      to.back().connect(e);
    }
    OldResultHeader done;
    wire::ResultHeader other_run;  // the current format, of another run
    other_run.kind = wire::ResultKind::done;
    other_run.run = 42;
    wire::ExchangeHeader stray;
    stray.to = 0;
    stray.from = 1;
    const std::string junk(100, 'x');
    while (!over) {
      for (auto& s : to) {
        s.send(zmq::buffer(junk), zmq::send_flags::dontwait);                      // one 100-byte frame
        s.send(zmq::const_buffer(&done, sizeof done), zmq::send_flags::dontwait);  // a forged done
        s.send(zmq::const_buffer(&other_run, sizeof other_run), zmq::send_flags::sndmore);
        s.send(zmq::buffer(junk), zmq::send_flags::dontwait);
        s.send(zmq::const_buffer(&stray, sizeof stray), zmq::send_flags::sndmore);
        s.send(zmq::buffer(junk), zmq::send_flags::sndmore);
        s.send(zmq::buffer(junk), zmq::send_flags::dontwait);  // three frames
        sent += 4;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  test::MemorySink sink;
  RunSummary r;
  try {
    r = run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr);
  } catch (...) {
    over = true;
    attacker.join();
    throw;
  }
  over = true;
  attacker.join();
  std::filesystem::remove_all(dir);
  INFO("stray messages sent: " << sent.load());
  CHECK(sent.load() > 0);
  REQUIRE(sink.states.size() == reference.states.size());
  bool identical = true;
  for (std::size_t i = 0; i < sink.states.size(); ++i) identical = identical && sink.states[i] == reference.states[i];
  CHECK(identical);
  for (const std::string& e : pool.errors) CHECK(e.empty());
}

TEST_CASE("a keyed run (CURVE with the ZAP handler) equals the one-process run and an unlisted coordinator gets no answer",
          "[runtime][cluster][wire]") {
  const Model m = chain_run(12, 60);
  const RunOptions o = options_from_model(m);
  const test::MemorySink reference = one_process(m);
  const CurveKeyPair coordinator = make_curve_keys(), intruder = make_curve_keys();
  const std::vector<CurveKeyPair> keys{make_curve_keys(), make_curve_keys()};
  const ClusterKeys admit{coordinator.public_key, {keys[0].public_key, keys[1].public_key}};
  for (const bool listed : {true, false}) {
    INFO((listed ? "listed" : "unlisted") << " coordinator");
    std::vector<std::string> refusals(2);
    {  // the workers are joined at the end of the block: then they have logged what they refused
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"}, [&](std::size_t i, WorkerOptions& w) {
      w.keys = keys[i];
      w.admit = admit;
      w.idle_timeout_s = listed ? 30.0 : 3.0;
      w.log = [&refusals, i](const std::string& line) {
        if (line.find("refused") != std::string::npos) refusals[i] = line;
      };
    });
    ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
    c.insecure = Insecure::no;
    c.keys = listed ? coordinator : intruder;
    c.coordinator_key = c.keys->public_key;
    c.timeouts.connect_s = 1.0;
    for (std::size_t i = 0; i < c.workers.size(); ++i) {
      c.workers[i].data_bind = "tcp://127.0.0.1:*";
      c.workers[i].public_key = keys[i].public_key;
    }
    const Decomposition d = decompose(m, cluster_submodels(c));
    test::MemorySink sink;
    if (listed) {
      run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr);
      REQUIRE(sink.states.size() == reference.states.size());
      CHECK(sink.states.back() == reference.states.back());
      for (const std::string& e : pool.errors) CHECK(e.empty());
    } else {
      CHECK_THROWS_WITH(run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr), Catch::Contains("did not answer within 1 s"));
      CHECK(sink.states.empty());
    }
    }
    if (!listed) CHECK_THAT(refusals[0], Catch::Contains("key " + intruder.public_key + " is not in the cluster file"));
  }
}

TEST_CASE("a worker ends its run when the model's parts come longer than its set-up announced", "[runtime][cluster][wire]") {
  ThreadWorkers pool({"tcp://127.0.0.1:*"});
  {
    zmq::context_t ctx;
    zmq::socket_t coordinator(ctx, zmq::socket_type::dealer);
    coordinator.set(zmq::sockopt::linger, 0);
    coordinator.connect(pool.endpoints[0]);
    const std::string run = R"("run":"0123456789abcdef")";
    const zmq::message_t ok =
        ask(coordinator, R"({"type":"hello","program":")" + std::string(MBSFLOW_PROGRAM_VERSION) +
                             R"(","protocol":)" + std::to_string(cluster_protocol_version) + "," + run +
                             R"(,"timeouts":{"connect_s":10,"heartbeat_s":0.5,"lost_s":3}})");
    REQUIRE(ok.to_string().find("hello_ok") != std::string::npos);
    coordinator.send(zmq::buffer(R"({"type":"setup","model_bytes":10,)" + run + "}"), zmq::send_flags::none);
    coordinator.send(zmq::buffer(R"({"type":"model_part",)" + run + "}"), zmq::send_flags::sndmore);
    coordinator.send(zmq::buffer(std::string(20, 'x')), zmq::send_flags::none);
    for (auto& t : pool.threads) t.join();  // the worker gives the run up at once
    pool.threads.clear();
  }
  CHECK_THAT(pool.errors[0], Catch::Contains("the set-up's model came longer than announced"));
}
