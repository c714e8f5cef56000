#include "submodel_links.hpp"

#include <algorithm>
#include <map>

#include "mbsflow/graph/force_element.hpp"

namespace mbsflow {

BodyLinks::BodyLinks(const Model& m) : joints(m.bodies.size()), elements(m.bodies.size()) {
  for (std::size_t j = 0; j < m.joints.size(); ++j) {
    const Joint& jt = m.joints[j];
    joints[static_cast<std::size_t>(jt.body2)].push_back(static_cast<int>(j));
    if (jt.body1 != ground && jt.body1 != jt.body2) joints[static_cast<std::size_t>(jt.body1)].push_back(static_cast<int>(j));
  }
  for (std::size_t e = 0; e < m.force_elements.size(); ++e) {
    std::vector<int> bodies = m.force_elements[e]->bodies();
    std::sort(bodies.begin(), bodies.end());
    bodies.erase(std::unique(bodies.begin(), bodies.end()), bodies.end());
    for (int b : bodies) elements[static_cast<std::size_t>(b)].push_back(static_cast<int>(e));
  }
}

namespace {

// 0: not local; 1: own; 2: borrowed.
std::vector<char> membership(std::size_t bodies, const Submodel& s) {
  std::vector<char> in(bodies, 0);
  for (int b : s.own) in[static_cast<std::size_t>(b)] = 1;
  for (int b : s.borrowed) in[static_cast<std::size_t>(b)] = 2;
  return in;
}

}  // namespace

void link_submodels(const Model& m, Decomposition& d) {
  const BodyLinks links(m);
  for (Submodel& s : d.submodels) {
    const std::vector<char> in = membership(m.bodies.size(), s);
    std::vector<char> near(m.bodies.size(), 0);  // joined to an own body
    std::vector<int> joints, ghosts;
    auto visit = [&](int b, int other) {
      if (other == ground) return;
      const auto o = static_cast<std::size_t>(other);
      if (in[static_cast<std::size_t>(b)] == 1 && in[o] != 1) near[o] = 1;
      if (!in[o]) ghosts.push_back(other);
    };
    for (const std::vector<int>* list : {&s.own, &s.borrowed})
      for (int b : *list) {
        for (int j : links.joints[static_cast<std::size_t>(b)]) {
          const Joint& jt = m.joints[static_cast<std::size_t>(j)];
          joints.push_back(j);
          visit(b, jt.body1 == b ? jt.body2 : jt.body1);
        }
        for (int e : links.elements[static_cast<std::size_t>(b)])
          for (int other : m.force_elements[static_cast<std::size_t>(e)]->bodies()) visit(b, other);
      }
    std::sort(joints.begin(), joints.end());
    joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
    std::sort(ghosts.begin(), ghosts.end());
    ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
    s.joints = std::move(joints);
    s.ghosts = std::move(ghosts);
    s.cut_joints = 0;
    for (int j : s.joints) {
      const Joint& jt = m.joints[static_cast<std::size_t>(j)];
      if ((jt.body1 != ground && !in[static_cast<std::size_t>(jt.body1)]) || !in[static_cast<std::size_t>(jt.body2)]) ++s.cut_joints;
    }
    // Borrowed bodies and ghosts come from their owners, in ascending global order.
    std::vector<int> pulled = s.borrowed;
    pulled.insert(pulled.end(), s.ghosts.begin(), s.ghosts.end());
    std::sort(pulled.begin(), pulled.end());
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
  }
}

}  // namespace mbsflow
