// Overlapping submodels: what each one borrows, and what it still takes as ghosts.
#include <catch2/catch.hpp>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"

using namespace mbsflow;

TEST_CASE("joint rates: a bushing's fastest mode of its two bodies alone, infinite for a rigid joint", "[graph][overlap]") {
  ChainParams c;
  c.bodies = 3;
  c.rotational_stiffness = 0.0;
  c.damping_ratio = 0.0;
  Model m = make_chain(c);
  const std::vector<double> rate = joint_rates(m);
  REQUIRE(rate.size() == 3);
  // Translation: k (1/m + 1/m); rotation about y: k (l/2)^2 (1/I + 1/I), I = m l^2 / 12: faster.
  const double l = c.link_length, inertia = c.mass * l * l / 12.0;
  const double rotation = c.stiffness * 0.25 * l * l * 2.0 / inertia;
  CHECK(rate[1] == Approx(std::sqrt(rotation)).epsilon(1e-12));
  CHECK(rate[0] == Approx(std::sqrt(0.5 * rotation)).epsilon(1e-12));  // to the ground: one body moves
  m.joints[1].type = JointType::revolute;
  CHECK(std::isinf(joint_rates(m)[1]));
}

TEST_CASE("with_overlap: each submodel borrows the bodies within reach, ghosts lie beyond them", "[graph][overlap]") {
  ChainParams c;
  c.bodies = 20;
  const Model m = make_chain(c);
  std::vector<int> part(20, 0);
  for (int b = 10; b < 20; ++b) part[static_cast<std::size_t>(b)] = 1;
  const Decomposition d = decompose(m, part, 2);
  for (const Submodel& s : d.submodels) {
    CHECK(s.borrowed.empty());
    REQUIRE(s.exchanges.size() == 1);
    CHECK(s.exchanges[0].near == std::vector<int>{0});  // the one ghost is joined to an own body
  }
  const double hop = 1.0 / joint_rates(m)[5];  // every joint between two links alike
  const Decomposition o = with_overlap(m, d, 3.5 * hop);
  const Submodel& a = o.submodels[0];
  const Submodel& b = o.submodels[1];
  CHECK(a.own == d.submodels[0].own);
  CHECK(a.borrowed == std::vector<int>{10, 11, 12});
  CHECK(a.ghosts == std::vector<int>{13});
  CHECK(b.borrowed == std::vector<int>{7, 8, 9});
  CHECK(b.ghosts == std::vector<int>{6});
  CHECK(a.integrated() == 13);
  CHECK(a.local_index(12) == 12);
  CHECK(a.local_index(13) == 13);
  CHECK(b.local_index(7) == 10);  // own first, then borrowed, then ghosts
  CHECK(b.local_index(6) == 13);
  CHECK(a.joints.size() == 14);  // the pin and j1 .. j13 (j13 reaches the ghost)
  CHECK(a.cut_joints == 1);
  REQUIRE(a.exchanges.size() == 1);
  const Submodel::Exchange& e = a.exchanges[0];
  CHECK(e.neighbour == 1);
  CHECK(e.from == std::vector<int>{0, 1, 2, 3});  // the owner's own bodies 10 .. 13
  CHECK(e.to == std::vector<int>{10, 11, 12, 13});
  CHECK(e.near == std::vector<int>{0});  // body 10, the one joined to an own body
  // The local model integrates the borrowed bodies: their joints and derivatives are there.
  const Model local = submodel_model(m, a);
  CHECK(local.bodies.size() == 14);
  CHECK(local.joints.size() == 14);
  // No reach: the decomposition itself.
  const Decomposition none = with_overlap(m, d, 0.0);
  CHECK(none.submodels[0].borrowed.empty());
  CHECK(none.submodels[0].ghosts == d.submodels[0].ghosts);
}
