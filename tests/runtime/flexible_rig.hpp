#pragma once
// The flexible-body rig of the partition and cluster tests: the lattice bar of
// analysis/flexible_part.hpp hung from the ground, rigid bodies joined to a node and to
// its frame.
#include <string>
#include <vector>

#include "analysis/flexible_part.hpp"
#include "test_support.hpp"

namespace mbsflow::test {

inline int add_body(Model& m, const char* name, double mass, Vec3 at) {
  m.bodies.push_back(test::make_body(name, mass, {0.02 * mass, 0.03 * mass, 0.04 * mass, 0, 0, 0}, at));
  return static_cast<int>(m.bodies.size()) - 1;
}

inline Vec3 offset(const Model& m, int from, int to) {
  const Vec3 &a = m.bodies[static_cast<std::size_t>(from)].position, &b = m.bodies[static_cast<std::size_t>(to)].position;
  return {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
}

// The lattice bar (flexible_part.hpp) hung from the ground by a bushing at node 1; body A
// on a spherical joint at node 24 (one rigid cluster with the part), B and C hung from A
// by bushings, D by a bushing at the bar's frame; gravity, everything swinging.
struct Rig {
  Model m;
  int frame, a, b, c, d;
};

// part: the bar's model alone (flexible_model, or read from its part file).
inline Rig hanging_rig(Model part = test::flexible_model(test::bar_part(4, {1, 2, 3, 24}))) {
  Rig r{std::move(part), 0, 0, 0, 0, 0};
  Model& m = r.m;
  m.name = "flexible_rig";
  m.gravity = {0, 0, -9.81};
  const FlexibleBody f = m.flexible.front();
  r.frame = f.frame;
  const Vec3 tip = m.bodies[static_cast<std::size_t>(f.nodes[3])].position;
  r.a = add_body(m, "A", 1.5, {tip[0] + 0.1, tip[1], tip[2]});
  r.b = add_body(m, "B", 0.8, {tip[0] + 0.3, tip[1], tip[2] - 0.1});
  r.c = add_body(m, "C", 0.6, {tip[0] + 0.5, tip[1], tip[2] - 0.2});
  r.d = add_body(m, "D", 0.9, {0.5, 0.05, -0.3});
  m.bodies[static_cast<std::size_t>(r.c)].velocity = {0.0, 0.4, 0.0};
  m.bodies[static_cast<std::size_t>(r.d)].velocity = {0.2, 0.0, 0.1};
  const Vec6 k{4e4, 4e4, 4e4, 40, 40, 40}, c{20, 20, 20, 0.1, 0.1, 0.1};
  m.joints.push_back(test::make_bushing(ground, f.nodes[0], m.bodies[static_cast<std::size_t>(f.nodes[0])].position, {}, k, c));
  m.joints.push_back(test::make_joint(JointType::spherical, r.a, f.nodes[3], offset(m, r.a, f.nodes[3]), {}));
  m.joints.push_back(test::make_bushing(r.a, r.b, offset(m, r.a, r.b), {}, {3e3, 3e3, 3e3, 5, 5, 5}, {2, 2, 2, 0.01, 0.01, 0.01}));
  m.joints.push_back(test::make_bushing(r.b, r.c, offset(m, r.b, r.c), {}, {2e3, 2e3, 2e3, 5, 5, 5}, {2, 2, 2, 0.01, 0.01, 0.01}));
  m.joints.push_back(test::make_bushing(r.frame, r.d, offset(m, r.frame, r.d), {}, {5e3, 5e3, 5e3, 5, 5, 5}, {3, 3, 3, 0.01, 0.01, 0.01}));
  for (std::size_t j = 0; j < m.joints.size(); ++j) m.joints[j].name = "j" + std::to_string(j);
  m.simulation.step = 2e-4;
  m.simulation.t_end = 0.1;
  m.simulation.output_every = 50;
  return r;
}

// Bodies 0..4 (the bar and its nodes) and A in part 0; B, C in part 1; D in part 2.
inline std::vector<int> three_parts(const Rig& r) {
  std::vector<int> part(r.m.bodies.size(), 0);
  part[static_cast<std::size_t>(r.b)] = part[static_cast<std::size_t>(r.c)] = 1;
  part[static_cast<std::size_t>(r.d)] = 2;
  return part;
}


}  // namespace mbsflow::test
