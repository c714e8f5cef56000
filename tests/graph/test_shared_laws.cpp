// Joints with the same force law and frames, and bodies with the same mass properties,
// share one compiled copy (shared_laws.hpp): equal means equal bit for bit, a shared
// copy changes no number, and a chain's compiled model stays a few dozen bytes a body.
#include <catch2/catch.hpp>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "shared_laws.hpp"

using namespace mbsflow;

TEST_CASE("distinct_by_bits numbers the sets in order of first use and tells 0.0 from -0.0", "[graph]") {
  const std::vector<double> values = {2.0, 0.0, 2.0, -0.0, 1.5, 0.0, 1.5, 2.0};
  const DistinctIndex d = distinct_by_bits(values.size(), [&](std::size_t i) {
    KeyWords<1> k;
    k.put(std::array<double, 1>{values[i]});
    return k.words;
  });
  CHECK(d.of_item == std::vector<int>{0, 1, 0, 2, 3, 1, 3, 0});
  CHECK(d.first == std::vector<int>{0, 1, 3, 4});

  // Many items over a few sets: every item finds its own set through the probing.
  const std::size_t n = 20000;
  const DistinctIndex many = distinct_by_bits(n, [](std::size_t i) {
    KeyWords<2> k;
    k.put(std::array<double, 2>{static_cast<double>(i % 7), static_cast<double>(i % 3)});
    return k.words;
  });
  REQUIRE(many.first.size() == 21);
  for (std::size_t i = 0; i < n; ++i) REQUIRE(many.first[static_cast<std::size_t>(many.of_item[i])] == static_cast<int>(i % 21));
}

TEST_CASE("a chain's bushings share one law: its compiled model is a few dozen bytes a body", "[graph]") {
  ChainParams p;
  p.bodies = 2000;
  const Model same = make_chain(p);
  const MultibodySystem shared(same);
  const double per_body = static_cast<double>(shared.memory_use().compiled) / 2000.0;
  CHECK(per_body < 100.0);

  // Each joint its own stiffness and each body its own mass: every law is held.
  Model own = same;
  for (std::size_t k = 0; k < own.joints.size(); ++k) own.joints[k].stiffness.set(0, own.joints[k].stiffness[0] * (1.0 + 1e-9 * static_cast<double>(k)));
  for (std::size_t i = 0; i < own.bodies.size(); ++i) own.bodies[i].mass *= 1.0 + 1e-9 * static_cast<double>(i);
  const MultibodySystem distinct(own);
  CHECK(static_cast<double>(distinct.memory_use().compiled) / 2000.0 > per_body + 300.0);
}

TEST_CASE("a joint or body that differs in one bit keeps its own law and only its bodies' rates change", "[graph]") {
  ChainParams p;
  p.bodies = 40;
  const Model base = make_chain(p);
  MultibodySystem a(base);
  Eigen::VectorXd y = a.initial_state();
  for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += 1e-3 * std::sin(0.7 * static_cast<double>(i));  // away from rest
  Eigen::VectorXd da(a.dimension()), db(a.dimension());
  a.rhs(0.0, y, da);

  // Joint 17's stiffness along x and body 30's mass each with the top bit of its mantissa
  // flipped.
  const auto flipped = [](double x) { return std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) ^ (std::uint64_t{1} << 51)); };
  Model changed = base;
  const int joint = 17, body = 30;
  changed.joints[joint].stiffness.set(0, flipped(changed.joints[joint].stiffness[0]));
  changed.bodies[body].mass = flipped(changed.bodies[body].mass);
  MultibodySystem b(changed);
  b.rhs(0.0, y, db);
  const StateLayout l = a.layout();
  std::vector<int> moved;
  for (Eigen::Index i = 0; i < l.bodies; ++i)
    if (da.segment<3>(l.velocity(i)) != db.segment<3>(l.velocity(i)) ||
        da.segment<3>(l.angular_velocity(i)) != db.segment<3>(l.angular_velocity(i)))
      moved.push_back(static_cast<int>(i));
  const int b1 = changed.joints[joint].body1, b2 = changed.joints[joint].body2;
  std::vector<int> expected = {b1, b2, body};
  std::sort(expected.begin(), expected.end());
  expected.erase(std::remove(expected.begin(), expected.end(), ground), expected.end());
  CHECK(moved == expected);
}
