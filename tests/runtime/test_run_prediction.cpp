#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "run_prediction.hpp"

using namespace mbsflow;

TEST_CASE("run prediction: compute of the slowest submodel plus its host's messages from other hosts", "[runtime][plan]") {
  ChainParams c;
  c.bodies = 12;
  const Model m = make_chain(c);
  const Decomposition d = decompose(m, 4, Partitioner::band);  // a chain: 0-1-2-3 in a row
  const Hockney net{1e-5, 1e8};
  const double per_cost = 1e-9;
  const StagePrediction p = predict_stage(d, 2, 2, per_cost, net);
  // One boundary body crosses between hosts each way: submodels 1 and 2.
  CHECK(p.messages == 2);
  CHECK(p.bytes == 2 * boundary_message_bytes(1));
  CHECK(boundary_message_bytes(1) == 13 * 8 + 40);
  CHECK(p.exchange_s == Approx(1e-5 + 144 / 1e8).epsilon(1e-12));
  double slowest = 0.0;
  for (const Submodel& s : d.submodels) slowest = std::max(slowest, per_cost * s.estimated_time());
  CHECK(p.compute_s <= slowest);
  CHECK(p.stage_s() == Approx(p.compute_s + p.exchange_s));
  CHECK(p.cut_joints == d.cut_joints);
  // On one host the threads share memory: no messages.
  const StagePrediction one = predict_stage(d, 1, 4, per_cost, net);
  CHECK(one.messages == 0);
  CHECK(one.exchange_s == 0.0);
  CHECK(one.compute_s == Approx(slowest).epsilon(1e-12));
  // Four hosts of one thread: the inner hosts hear from two neighbours.
  const StagePrediction four = predict_stage(d, 4, 1, per_cost, net);
  CHECK(four.messages == 6);
  CHECK(four.exchange_s == Approx(2 * net.time(144)).epsilon(1e-12));
  CHECK_THROWS_AS(predict_stage(d, 3, 1, per_cost, net), InputError);
}

TEST_CASE("measure exchange: every round trip is answered and the last reply is not lost at close", "[runtime][plan]") {
  // Each measurement ends with the echo's socket closing right after its last reply: a
  // socket that drops what it still holds at close (linger 0) loses that reply now and
  // then, and the measurement waited for it for ever (bench parallel hung in CI).
  for (int i = 0; i < 150; ++i) {
    const std::string transport = i % 3 == 0 ? "ipc" : "tcp";
    const std::vector<ExchangeSample> s = measure_exchange(transport, {65536}, 1);
    REQUIRE(s.size() == 1);
    CHECK(s[0].bytes == 65536);
    CHECK(s[0].seconds > 0.0);
  }
}

TEST_CASE("hockney fit: alpha and beta of exact samples", "[runtime][plan]") {
  const Hockney h = fit_hockney({{0, 2e-5}, {1000, 2e-5 + 1000 / 5e8}, {65536, 2e-5 + 65536 / 5e8}});
  CHECK(h.alpha == Approx(2e-5).epsilon(1e-9));
  CHECK(h.beta == Approx(5e8).epsilon(1e-9));
  CHECK(h.time(1e6) == Approx(2e-5 + 1e6 / 5e8).epsilon(1e-9));
  CHECK_THROWS_AS(fit_hockney({{0, 1e-5}}), InputError);
}
