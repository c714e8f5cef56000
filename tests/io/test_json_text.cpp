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
