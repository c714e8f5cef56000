// What the third reliability probe found on the wire, replayed against a real worker over
// loopback: a set-up announcing a huge model, options out of range, large messages from
// unknown peers, and a hello followed by nothing. The worker refuses or gives up with a
// named error; the test process (which runs the worker on a thread) survives.
#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "cluster_wire.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "options_json.hpp"
#include "thread_workers.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

const std::string run_id = R"("run":"0123456789abcdef")";

std::string hello(double connect_s = 10, double heartbeat_s = 0.5, double lost_s = 3) {
  return R"({"type":"hello","program":")" + std::string(MBSFLOW_PROGRAM_VERSION) + R"(","protocol":)" +
         std::to_string(cluster_protocol_version) + "," + run_id + R"(,"timeouts":{"connect_s":)" + std::to_string(connect_s) +
         R"(,"heartbeat_s":)" + std::to_string(heartbeat_s) + R"(,"lost_s":)" + std::to_string(lost_s) + "}}";
}

// A coordinator's socket on worker `endpoint`, past the hello.
struct FakeCoordinator {
  zmq::context_t ctx;
  zmq::socket_t s{ctx, zmq::socket_type::dealer};
  explicit FakeCoordinator(const std::string& endpoint, const std::string& greeting = hello()) {
    s.set(zmq::sockopt::linger, 0);
    s.set(zmq::sockopt::rcvtimeo, 2000);
    s.connect(endpoint);
    s.send(zmq::buffer(greeting), zmq::send_flags::none);
    const std::string reply = next();  // heartbeats may come first
    INFO(reply);
    REQUIRE(reply.find("hello_ok") != std::string::npos);
  }
  void send(const std::string& text, zmq::send_flags f = zmq::send_flags::none) { s.send(zmq::buffer(text), f); }
  // The worker's next message other than a heartbeat ("" after 2 s of nothing else).
  std::string next() {
    zmq::message_t m;
    while (s.recv(m))
      if (m.to_string().find("\"heartbeat\"") == std::string::npos) return m.to_string();
    return "";
  }
  // A set-up of a one-submodel run of `model` with these options, then the model's text.
  void setup(const std::string& model, const std::string& options_json) {
    send(R"({"type":"setup","model_bytes":)" + std::to_string(model.size()) + R"(,"part_of_body":"0","submodels":1,)" +
         R"("worker_of":[0],"worker":0,"options":)" + options_json +
         R"(,"data_bind":"tcp://127.0.0.1:*","results_address":"tcp://127.0.0.1:1",)" + run_id + "}");
    send(R"({"type":"model_part",)" + run_id + "}", zmq::send_flags::sndmore);
    send(model);
  }
};

std::string one_body_model() {
  ChainParams p;
  p.bodies = 1;
  return model_to_json(make_chain(p));
}

std::string options_with(const std::string& key, const std::string& value) {
  nlohmann::json o = options_to_json(RunOptions{});
  o[key] = nlohmann::json::parse(value);
  return o.dump();
}

}  // namespace

TEST_CASE("a set-up announcing a model of 2^38 bytes costs nothing until the bytes come", "[runtime][cluster][wire]") {
  ThreadWorkers pool({"tcp://127.0.0.1:*"});
  {
    FakeCoordinator c(pool.endpoints[0]);
    c.send(R"({"type":"setup","model_bytes":274877906944,)" + run_id + "}");
    c.send(R"({"type":"model_part",)" + run_id + "}", zmq::send_flags::sndmore);
    c.send(std::string(1000, ' '));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    c.send(R"({"type":"abort","reason":"test over",)" + run_id + "}");
    for (auto& t : pool.threads) t.join();
    pool.threads.clear();
  }
  // The worker was alive to take the abort: it reserved nothing for what was announced.
  CHECK_THAT(pool.errors[0], Catch::Contains("stopped by the coordinator: test over"));
}

TEST_CASE("run options from the wire pass the validation of the command line: out of range is refused, never used",
          "[runtime][cluster][wire]") {
  const std::string model = one_body_model();
  for (const auto& [key, value, says] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"output_every", "0", "output_every is not an integer in [1,"},
           {"output_every", "1e300", "output_every is not an integer in [1,"},
           {"output_every", "-5", "output_every is not an integer in [1,"},
           {"rtol", "-1", "rtol and atol must be positive finite numbers"},
           {"step", "0", "the step must be a positive finite number"},
           {"t_end", "-1", "t_end must be greater than t_start"},
           {"linear_solver", "\"gauss\"", "unknown linear solver 'gauss' (auto, dense, banded, klu or sparselu)"}}) {
    INFO(key << " = " << value);
    ThreadWorkers pool({"tcp://127.0.0.1:*"});
    {
      FakeCoordinator c(pool.endpoints[0]);
      c.setup(model, options_with(key, value));
      CHECK_THAT(c.next(), Catch::Contains(says));
      for (auto& t : pool.threads) t.join();
      pool.threads.clear();
    }
    CHECK_THAT(pool.errors[0], Catch::Contains("cannot set up the run: run options from the coordinator: "));
  }
  // The loose-coupling options too.
  nlohmann::json loose = {{"macro_step", 0.01}, {"extrapolation", 7},         {"max_lag", 0},       {"exact_lag", false},
                          {"methods", nlohmann::json::array()}, {"overlap", -1.0}, {"coupling_tol", 0.0}};
  CHECK_THROWS_WITH(loose_from_json(loose), Catch::Contains("extrapolation is not an integer in [0, 2]"));
  loose["extrapolation"] = 1;
  loose["macro_step"] = -1.0;
  CHECK_THROWS_WITH(loose_from_json(loose), Catch::Contains("macro_step"));
}

TEST_CASE("a message is parsed only once its sender is known, and never at more than a small multiple of its size",
          "[runtime][cluster][wire]") {
  // A hello padded past 64 KiB from an unknown peer is dropped unread (it was taken before).
  ThreadWorkers pool({"tcp://127.0.0.1:*"});
  {
    zmq::context_t ctx;
    zmq::socket_t stranger(ctx, zmq::socket_type::dealer);
    stranger.set(zmq::sockopt::linger, 0);
    stranger.set(zmq::sockopt::rcvtimeo, 500);
    stranger.connect(pool.endpoints[0]);
    std::string padded = hello();
    padded.insert(padded.size() - 1, R"(,"pad":")" + std::string(70 * 1024, 'x') + "\"");
    stranger.send(zmq::buffer(padded), zmq::send_flags::none);
    zmq::message_t reply;
    CHECK(!stranger.recv(reply));  // no hello_ok, no refusal: not read
    // The worker still takes a coordinator; another peer then gets a refusal, its message unread.
    FakeCoordinator c(pool.endpoints[0]);
    stranger.send(zmq::buffer(std::string(1 << 20, '[')), zmq::send_flags::none);
    REQUIRE(stranger.recv(reply));
    CHECK_THAT(reply.to_string(), Catch::Contains("busy with another run"));
    c.send(R"({"type":"abort","reason":"test over",)" + run_id + "}");
    for (auto& t : pool.threads) t.join();
    pool.threads.clear();
  }
  CHECK_THAT(pool.errors[0], Catch::Contains("stopped by the coordinator"));

  // The bound: a list of ten million small integers (20 MB) would cost about 25 bytes a
  // byte in nlohmann::json; such a message is refused, the same list as text is taken.
  std::vector<int> parts(10'000'000, 3);
  std::string as_list = R"({"type":"setup","part_of_body":[)";
  for (std::size_t i = 0; i < parts.size(); ++i) as_list += i ? ",3" : "3";
  as_list += "]}";
  const std::string as_text = nlohmann::json({{"type", "setup"}, {"part_of_body", wire::integer_list_text(parts)}}).dump();
  CHECK(wire::parsed_bytes_bound(as_list) > wire::max_parse_factor * as_list.size());
  CHECK(!wire::parse_control(zmq::message_t(as_list.data(), as_list.size())));
  const auto taken = wire::parse_control(zmq::message_t(as_text.data(), as_text.size()));
  REQUIRE(taken);
  CHECK(wire::integer_list((*taken)["part_of_body"].get<std::string>(), 0, 3) == std::optional<std::vector<int>>(parts));
  CHECK(!wire::integer_list("0,1,x", 0, 3));
  CHECK(!wire::integer_list("0,4", 0, 3));
  CHECK(!wire::integer_list("0,,1", 0, 3));
  CHECK(wire::integer_list("", 0, 3) == std::optional<std::vector<int>>(std::vector<int>{}));
}

TEST_CASE("a hello followed by heartbeats and no set-up holds a worker no longer than connect_s + lost_s",
          "[runtime][cluster][wire]") {
  ThreadWorkers pool({"tcp://127.0.0.1:*"});
  const auto start = std::chrono::steady_clock::now();
  {
    FakeCoordinator c(pool.endpoints[0], hello(0.5, 0.2, 1.0));
    // Heartbeats for 4 s: the worker must give up at 1.5 s all the same.
    for (int i = 0; i < 20; ++i) {
      c.send(R"({"type":"heartbeat",)" + run_id + "}");
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    for (auto& t : pool.threads) t.join();
    pool.threads.clear();
  }
  CHECK_THAT(pool.errors[0], Catch::Contains("the coordinator sent no setup within 1.5 s"));
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 6.0);
}
