#include "submodel_links.hpp"

#include <algorithm>
#include <map>

#include "mbsflow/graph/force_element.hpp"

namespace mbsflow {

BodyLinks::BodyLinks(const Model& m) {
  build_body_csr(m.bodies.size(), [&](auto emit) {
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
      const Joint& jt = m.joints[j];
      emit(jt.body2, static_cast<int>(j));
      if (jt.body1 != ground && jt.body1 != jt.body2) emit(jt.body1, static_cast<int>(j));
    }
  }, joints.start, joints.list);
  std::vector<std::vector<int>> element_bodies(m.force_elements.size());
  for (std::size_t e = 0; e < m.force_elements.size(); ++e) {
    std::vector<int>& bodies = element_bodies[e] = m.force_elements[e]->bodies();
    std::sort(bodies.begin(), bodies.end());
    bodies.erase(std::unique(bodies.begin(), bodies.end()), bodies.end());
  }
  build_body_csr(m.bodies.size(), [&](auto emit) {
    for (std::size_t e = 0; e < element_bodies.size(); ++e)
      for (int b : element_bodies[e]) emit(b, static_cast<int>(e));
  }, elements.start, elements.list);
}

namespace {

enum Membership : char { outside, own, borrowed, ghost };

// The marked items in ascending order, their marks cleared: sorted where they are few, read
// off the marks in order where they are many (a submodel of a large model).
std::vector<int> ascending_and_unmarked(std::vector<int> items, std::vector<char>& mark) {
  if (items.size() * 16 < mark.size()) {
    std::sort(items.begin(), items.end());
  } else {
    items.clear();
    for (std::size_t i = 0; i < mark.size(); ++i)
      if (mark[i]) items.push_back(static_cast<int>(i));
  }
  for (int i : items) mark[static_cast<std::size_t>(i)] = 0;
  return items;
}

}  // namespace

void link_submodels(const Model& m, Decomposition& d) {
  const BodyLinks links(m);
  std::vector<char> in(m.bodies.size(), outside);
  std::vector<char> near(m.bodies.size(), 0);  // joined to an own body
  std::vector<char> joint_seen(m.joints.size(), 0);
  for (Submodel& s : d.submodels) {
    for (int b : s.own) in[static_cast<std::size_t>(b)] = own;
    for (int b : s.borrowed) in[static_cast<std::size_t>(b)] = borrowed;
    auto integrated = [&](int b) { return in[static_cast<std::size_t>(b)] == own || in[static_cast<std::size_t>(b)] == borrowed; };
    std::vector<int> joints, ghosts;
    auto visit = [&](int b, int other) {
      if (other == ground) return;
      const auto o = static_cast<std::size_t>(other);
      if (in[static_cast<std::size_t>(b)] == own && in[o] != own) near[o] = 1;
      if (in[o] == outside) {
        in[o] = ghost;
        ghosts.push_back(other);
      }
    };
    for (const std::vector<int>* list : {&s.own, &s.borrowed})
      for (int b : *list) {
        for (int j : links.joints[static_cast<std::size_t>(b)]) {
          const Joint& jt = m.joints[static_cast<std::size_t>(j)];
          if (!joint_seen[static_cast<std::size_t>(j)]) {
            joint_seen[static_cast<std::size_t>(j)] = 1;
            joints.push_back(j);
          }
          visit(b, jt.body1 == b ? jt.body2 : jt.body1);
        }
        for (int e : links.elements[static_cast<std::size_t>(b)])
          for (int other : m.force_elements[static_cast<std::size_t>(e)]->bodies()) visit(b, other);
      }
    s.joints = ascending_and_unmarked(std::move(joints), joint_seen);
    std::sort(ghosts.begin(), ghosts.end());  // few: the bodies just past the cut
    s.ghosts = std::move(ghosts);
    s.cut_joints = 0;
    for (int j : s.joints) {
      const Joint& jt = m.joints[static_cast<std::size_t>(j)];
      if ((jt.body1 != ground && !integrated(jt.body1)) || !integrated(jt.body2)) ++s.cut_joints;
    }
    // Borrowed bodies and ghosts come from their owners, in ascending global order.
    std::vector<int> pulled(s.borrowed.size() + s.ghosts.size());
    std::merge(s.borrowed.begin(), s.borrowed.end(), s.ghosts.begin(), s.ghosts.end(), pulled.begin());
    std::map<int, Submodel::Exchange> by_owner;
    for (int g : pulled) {
      const int owner = d.part_of_body[static_cast<std::size_t>(g)];
      Submodel::Exchange& e = by_owner[owner];
      e.neighbour = owner;
      if (near[static_cast<std::size_t>(g)]) e.near.push_back(static_cast<int>(e.from.size()));
      e.from.push_back(d.submodels[static_cast<std::size_t>(owner)].local_index(g));
      e.to.push_back(s.local_index(g));
    }
    s.exchanges.clear();
    for (auto& [owner, e] : by_owner) s.exchanges.push_back(std::move(e));
    for (int b : s.own) in[static_cast<std::size_t>(b)] = outside;
    for (int b : pulled) {
      in[static_cast<std::size_t>(b)] = outside;
      near[static_cast<std::size_t>(b)] = 0;
    }
  }
}

}  // namespace mbsflow
