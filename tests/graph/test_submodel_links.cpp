// What a submodel needs from the rest (submodel_links.hpp), against its definition
// computed the plain way, and the per-body lists it is built from (body_csr.hpp).
#include <algorithm>
#include <catch2/catch.hpp>
#include <set>
#include <utility>
#include <vector>

#include "body_csr.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/generators.hpp"

using namespace mbsflow;

TEST_CASE("per-body lists keep each body's items in the order they were given", "[decomposition]") {
  const std::vector<std::pair<int, int>> pairs{{2, 10}, {0, 11}, {2, 12}, {3, 13}, {0, 14}, {2, 15}};
  BodyCsr csr;
  build_body_csr(5, [&](auto emit) {
    for (const auto& [body, item] : pairs) emit(body, item);
  }, csr.start, csr.list);
  REQUIRE(csr.start == std::vector<int>{0, 2, 2, 5, 6, 6});
  auto list = [&](std::size_t b) { return std::vector<int>(csr[b].begin(), csr[b].end()); };
  CHECK(list(0) == std::vector<int>{11, 14});
  CHECK(list(1).empty());
  CHECK(list(2) == std::vector<int>{10, 12, 15});
  CHECK(list(3) == std::vector<int>{13});
  CHECK(list(4).empty());
}

TEST_CASE("each submodel's joints, ghosts and cut joints are those its definition gives, for few and for many submodels", "[decomposition]") {
  GridParams gp;
  gp.rows = 12;
  gp.cols = 12;
  const Model m = make_grid(gp);
  // 2 submodels hold half the joints each, 48 only a few: both ways of listing them.
  for (int k : {2, 48}) {
    INFO(k << " submodels");
    const Decomposition d = decompose(m, k, Partitioner::band);
    for (const Submodel& s : d.submodels) {
      std::set<int> local(s.own.begin(), s.own.end());
      local.insert(s.borrowed.begin(), s.borrowed.end());
      std::vector<int> joints;
      std::set<int> ghosts;
      int cut = 0;
      for (std::size_t j = 0; j < m.joints.size(); ++j) {
        const int a = m.joints[j].body1, b = m.joints[j].body2;
        const bool a_in = a == ground || local.count(a) > 0, b_in = local.count(b) > 0;
        if (!((a != ground && local.count(a)) || b_in)) continue;
        joints.push_back(static_cast<int>(j));
        if (!a_in) ghosts.insert(a);
        if (!b_in) ghosts.insert(b);
        if (!a_in || !b_in) ++cut;
      }
      CHECK(s.joints == joints);
      CHECK(s.ghosts == std::vector<int>(ghosts.begin(), ghosts.end()));
      CHECK(s.cut_joints == cut);
      // Every ghost comes from its owner, in ascending order.
      std::vector<int> pulled;
      for (const Submodel::Exchange& e : s.exchanges)
        for (int from : e.from) pulled.push_back(d.submodels[static_cast<std::size_t>(e.neighbour)].own[static_cast<std::size_t>(from)]);
      std::sort(pulled.begin(), pulled.end());
      CHECK(pulled == s.ghosts);
    }
  }
}
