#include <catch2/catch.hpp>

#include "json_locations.hpp"

using namespace mbsflow;

TEST_CASE("JSON locations: line and column of values and keys by field path", "[io]") {
  const std::string text = "{\n  \"a\": 1,\n  \"list\": [\n    {\"x\": [1, 2]},\n    \"s\\\"q\"\n  ]\n}\n";
  const JsonLocations loc(text);
  CHECK(loc.value("a").line == 2);
  CHECK(loc.value("a").column == 8);
  CHECK(loc.key("a").column == 3);
  CHECK(loc.value("list[0]").line == 4);
  CHECK(loc.value("list[0]").column == 5);
  CHECK(loc.value("list[0].x[1]").column == 15);
  CHECK(loc.value("list[1]").line == 5);
  CHECK(loc.value("missing").line == 0);
}
