// Counts and ordinals in messages.
#include <catch2/catch.hpp>

#include "mbsflow/words.hpp"

using namespace mbsflow;

TEST_CASE("counts take the singular for one and the plural otherwise", "[base]") {
  CHECK(count_of(1, "body", "bodies") == "1 body");
  CHECK(count_of(0, "body", "bodies") == "0 bodies");
  CHECK(count_of(2, "joint") == "2 joints");
  CHECK(count_of(1, "piece") == "1 piece");
}

TEST_CASE("ordinals: 1st 2nd 3rd 4th, 11th 12th 13th, 21st 22nd 23rd, 111th", "[base]") {
  CHECK(ordinal(1) == "1st");
  CHECK(ordinal(2) == "2nd");
  CHECK(ordinal(3) == "3rd");
  CHECK(ordinal(4) == "4th");
  CHECK(ordinal(11) == "11th");
  CHECK(ordinal(12) == "12th");
  CHECK(ordinal(13) == "13th");
  CHECK(ordinal(21) == "21st");
  CHECK(ordinal(22) == "22nd");
  CHECK(ordinal(103) == "103rd");
  CHECK(ordinal(111) == "111th");
}
