// Members most items leave at their defaults, held behind a pointer (rare_value.hpp).
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/graph/generators.hpp"
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

TEST_CASE("copies of a set value share one node until one of them is assigned", "[graph]") {
  Joint a;
  a.stiffness = {1.0, 2.0, 3.0, 4.0, 5.0, 6.0};
  Joint b = a;
  CHECK(&b.stiffness.get() == &a.stiffness.get());
  b.stiffness.set(2, 30.0);
  CHECK(&b.stiffness.get() != &a.stiffness.get());
  CHECK(a.stiffness == Vec6{1.0, 2.0, 3.0, 4.0, 5.0, 6.0});
  CHECK(b.stiffness == Vec6{1.0, 2.0, 30.0, 4.0, 5.0, 6.0});
  b.stiffness.set(2, 3.0);  // the same value again, in a node of its own
  CHECK(&b.stiffness.get() != &a.stiffness.get());
  b.stiffness.share(a.stiffness);
  CHECK(&b.stiffness.get() == &a.stiffness.get());
  b.stiffness = zeros6;
  CHECK(b.stiffness.is_default());
  CHECK(a.stiffness[5] == 6.0);
}

TEST_CASE("values are shared only when equal bit for bit", "[graph]") {
  Joint a, b;
  a.point1 = {0.0, 1.0, 0.0};
  b.point1 = {-0.0, 1.0, 0.0};  // == compares equal; the bits differ
  CHECK(a.point1 == b.point1);
  b.point1.share(a.point1);
  CHECK(&b.point1.get() != &a.point1.get());
  CHECK(std::signbit(b.point1[0]));
  b.point2 = {-0.0, 0.0, 0.0};  // not the default's bits: kept
  CHECK_FALSE(b.point2.is_default());
}

TEST_CASE("joints passed through ValueSharing store each repeated value once", "[graph]") {
  ValueSharing shared;
  std::vector<Joint> joints;
  for (int i = 0; i < 10; ++i) {
    Joint j;
    j.point1 = {0.5, 0.0, 0.0};
    j.point2 = {-0.5, 0.0, 0.0};
    j.stiffness = {1e4, 1e4, 1e4, 10.0, 10.0, 10.0};
    j.damping = {1.0, 1.0, 1.0, 0.1, 0.1, 0.1};
    if (i == 7) j.damping.set(0, 2.0);
    shared(j);
    joints.push_back(j);
  }
  for (const Joint& j : joints) {
    CHECK(&j.point1.get() == &joints[0].point1.get());
    CHECK(&j.point2.get() == &joints[0].point2.get());
    CHECK(&j.stiffness.get() == &joints[0].stiffness.get());
  }
  CHECK(&joints[9].damping.get() == &joints[0].damping.get());
  CHECK(&joints[7].damping.get() != &joints[0].damping.get());
  CHECK(joints[7].damping[0] == 2.0);
  CHECK(joints[8].damping[0] == 1.0);
}

TEST_CASE("joint and body records stay small", "[graph]") {
  STATIC_REQUIRE(sizeof(Joint) <= 136);
  STATIC_REQUIRE(sizeof(Body) <= 152);
  Body b;
  CHECK(b.inertia == unit_inertia);
  CHECK(b.inertia.is_default());
}

TEST_CASE("a generated grid's joints share their stiffness and damping and points and its bodies their inertia", "[graph]") {
  GridParams p;
  p.rows = 4;
  p.cols = 5;
  const Model m = make_grid(p);
  const Joint* x = nullptr;
  const Joint* z = nullptr;
  for (const Joint& j : m.joints) {
    CHECK(&j.stiffness.get() == &m.joints[0].stiffness.get());
    if (j.name[0] == 'x') {
      if (!x) x = &j;
      CHECK(&j.damping.get() == &x->damping.get());
      CHECK(&j.point1.get() == &x->point1.get());
      CHECK(&j.point2.get() == &x->point2.get());
    }
    if (j.name[0] == 'z') {
      if (!z) z = &j;
      CHECK(&j.point2.get() == &z->point2.get());
      CHECK(&j.damping.get() == &x->damping.get());  // the same reduced mass
    }
  }
  REQUIRE(x);
  REQUIRE(z);
  for (const Body& b : m.bodies) CHECK(&b.inertia.get() == &m.bodies[0].inertia.get());
  CHECK(x->point1 == Vec3{0.5 * p.spacing, 0.0, 0.0});
  CHECK(z->point2 == Vec3{0.0, 0.0, -0.5 * p.spacing});
}
