#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "json_text.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"

using namespace mbsflow;

namespace {
std::string text_of(double v) {
  std::string s;
  json_text::write(s, v);
  return s;
}
}  // namespace

TEST_CASE("JSON text: numbers read back to the same double and keep a floating-point form", "[io]") {
  CHECK(text_of(1.0) == "1.0");
  CHECK(text_of(-3.0) == "-3.0");
  CHECK(text_of(0.1) == "0.1");
  CHECK(text_of(1e-6) == "1e-06");
  CHECK(text_of(std::numeric_limits<double>::quiet_NaN()) == "null");
  CHECK(text_of(-std::numeric_limits<double>::infinity()) == "null");
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> exponent(-300, 300);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const double v = std::ldexp(mantissa(rng), exponent(rng));
    const nlohmann::json back = nlohmann::json::parse(text_of(v));
    REQUIRE(back.is_number_float());
    REQUIRE(back.get<double>() == v);
  }
}

TEST_CASE("JSON text: strings are escaped so that a JSON parser reads them back whole", "[io]") {
  const std::string tricky = std::string("a\"b\\c\nd\te\x01\x1f/") + "z\xC3\xBCge";
  std::string s;
  {
    json_text::Object o(s);
    o("name", tricky)("n", 3)("ok", true)("v", std::vector<double>{1.5, 2.0});
  }
  const nlohmann::json j = nlohmann::json::parse(s);
  CHECK(j["name"] == tricky);
  CHECK(j["n"] == 3);
  CHECK(j["ok"] == true);
  CHECK(j["v"] == nlohmann::json::array({1.5, 2.0}));
}

TEST_CASE("a model with names that need escaping is written and read back unchanged", "[io]") {
  Model m = make_chain(ChainParams{});
  m.name = "chain \"quoted\"\n\\ z\xC3\xBCge";
  m.bodies[0].name = "link \"0\"\t";
  m.joints[1].name = "joint\\1";
  const std::string once = model_to_json(m);
  const Model back = read_model_text(once, "escaped.json");
  CHECK(back.name == m.name);
  CHECK(back.bodies[0].name == m.bodies[0].name);
  CHECK(back.joints[1].name == m.joints[1].name);
  CHECK(back.joints[1].body1 == m.joints[1].body1);
  CHECK(model_to_json(back) == once);
}

TEST_CASE("the model text writes values that records share as each record's own", "[io]") {
  // The writer formats a shared value once and reuses its text for the records that hold
  // the same node. Here forty stiffness nodes and twenty inertia nodes (more than it keeps)
  // are shared in turn, so that texts are reused and evicted: every record's text must
  // still hold its own numbers.
  GridParams gp;
  gp.rows = 10;
  gp.cols = 12;
  Model m = make_grid(gp);
  std::vector<Joint> joint_pool(40, m.joints[1]);
  for (std::size_t p = 0; p < joint_pool.size(); ++p) {
    joint_pool[p].stiffness.set(0, 1e5 + static_cast<double>(p));
    joint_pool[p].point1 = Vec3{0.01 * static_cast<double>(p), 0.0, 0.0};
  }
  std::vector<Body> body_pool(20, m.bodies[0]);
  for (std::size_t p = 0; p < body_pool.size(); ++p)
    body_pool[p].inertia = Vec6{0.1, 0.2, 0.3, p % 2 ? 0.001 * static_cast<double>(p) : 0.0, 0.0, 0.0};
  std::mt19937 g(3);
  for (Joint& j : m.joints) {
    const Joint& from = joint_pool[g() % joint_pool.size()];
    j.stiffness = from.stiffness;
    j.point1 = from.point1;
  }
  for (Body& b : m.bodies) b.inertia = body_pool[g() % body_pool.size()].inertia;
  const nlohmann::json doc = nlohmann::json::parse(model_to_json(m));
  for (std::size_t k = 0; k < m.joints.size(); ++k) {
    const nlohmann::json& j = doc["joints"][k];
    for (std::size_t a = 0; a < 6; ++a) REQUIRE(j["stiffness"][a].get<double>() == m.joints[k].stiffness[a]);
    for (std::size_t a = 0; a < 3; ++a) REQUIRE(j["point1"][a].get<double>() == m.joints[k].point1[a]);
  }
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const nlohmann::json& inertia = doc["bodies"][i]["inertia"];
    const Vec6& expected = m.bodies[i].inertia.get();
    REQUIRE(inertia.size() == (expected[3] == 0.0 ? 3u : 6u));
    for (std::size_t a = 0; a < inertia.size(); ++a) REQUIRE(inertia[a].get<double>() == expected[a]);
  }
  CHECK(model_to_json(read_model_text(model_to_json(m), "shared.json")) == model_to_json(m));
}
