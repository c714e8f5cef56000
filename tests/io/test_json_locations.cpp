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

TEST_CASE("JSON locations: values past skipped strings with brackets and escapes and nested containers", "[io]") {
  const std::string text =
      "{\"s\": \"a]}[{\\\"\", \"deep\": {\"x\": [[1, {\"y\": \"]\"}], []]},\n"
      "\"after\": [true, null,\n  -1.5e3, {\"k\": 2}]}";
  const JsonLocations loc(text);
  CHECK(loc.value("s").column == 7);
  CHECK(loc.value("deep.x[0][1].y").column == 43);
  CHECK(loc.value("after").line == 2);
  CHECK(loc.value("after").column == 10);
  CHECK(loc.value("after[2]").line == 3);
  CHECK(loc.value("after[2]").column == 3);
  CHECK(loc.value("after[3].k").column == 17);
  CHECK(loc.key("after[3].k").column == 12);
  CHECK(loc.value("after[4]").line == 0);       // past the end of the list
  CHECK(loc.value("deep.x[0][1].z").line == 0);  // no such member
  CHECK(loc.value("aft").line == 0);            // a prefix of a key is not the key
}

TEST_CASE("JSON locations: keys written with escapes match their decoded paths", "[io]") {
  // "m\u0061ss" is the key mass; \ud83d\ude00 a surrogate pair (U+1F600, four bytes of UTF-8).
  const std::string text = "{\"m\\u0061ss\": 1, \"\\ud83d\\ude00\": 2, \"t\\tb\": 3}";
  const JsonLocations loc(text);
  CHECK(loc.value("mass").column == 15);
  CHECK(loc.value("\xF0\x9F\x98\x80").column == 34);
  CHECK(loc.value("t\tb").column == 45);
}

TEST_CASE("JSON locations: a search ends on text that is not JSON past the point of an error", "[io]") {
  // A reading error stops the parser; what follows was never checked. Each of these once
  // made the search loop for ever (a closer of the wrong kind inside a list or object).
  for (const std::string text : {"{\"list\": [1}", "{\"list\": [{\"a\": 1}}", "{\"o\": {\"a\": 1]", "[}", "{]", "[1, }}}"}) {
    const JsonLocations loc(text);
    CHECK(loc.value("list[5]").line == 0);
    CHECK(loc.value("o.b").line == 0);
  }
}
