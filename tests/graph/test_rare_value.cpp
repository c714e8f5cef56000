// Members most items leave at their defaults, held behind a pointer (rare_value.hpp).
#include <catch2/catch.hpp>

#include "mbsflow/graph/model.hpp"

using namespace mbsflow;

TEST_CASE("a joint's frames and preload read as their defaults and cost a pointer each until set", "[graph]") {
  STATIC_REQUIRE(sizeof(Defaulted<Quat, identity_frame>) == sizeof(void*));
  Joint j;
  CHECK(j.frame1 == identity_frame);
  CHECK(j.frame2.get() == Quat{1.0, 0.0, 0.0, 0.0});
  CHECK(j.preload == Vec6{});
  CHECK(j.frame1[0] == 1.0);
  j.frame1 = {0.0, 1.0, 0.0, 0.0};
  j.preload = {0.0, 4.0, 0.0, 0.0, 0.0, 0.5};
  CHECK(j.frame1 == Quat{0.0, 1.0, 0.0, 0.0});
  CHECK(j.frame1 != j.frame2);
  CHECK(j.preload[1] == 4.0);
  const Quat& read = j.frame1;  // reads as the value it stands for
  CHECK(read[1] == 1.0);
}

TEST_CASE("a set frame copies as a value and assigning the default lets it go", "[graph]") {
  Joint a;
  a.frame2 = {0.5, 0.5, 0.5, 0.5};
  Joint b = a;
  b.frame2 = {0.0, 0.0, 0.0, 1.0};
  CHECK(a.frame2 == Quat{0.5, 0.5, 0.5, 0.5});  // b's change is its own
  CHECK(b.frame2 == Quat{0.0, 0.0, 0.0, 1.0});
  b = a;
  CHECK(b.frame2 == a.frame2);
  b.frame2 = identity_frame;
  CHECK(b.frame2 == identity_frame);
  CHECK(a.frame2 == Quat{0.5, 0.5, 0.5, 0.5});
  Joint moved = std::move(a);
  CHECK(moved.frame2 == Quat{0.5, 0.5, 0.5, 0.5});
}
