#pragma once
// A model of rigid clusters joined by compliant elements, for the tests of partitioned and
// cluster runs: every cut passes between clusters, and the rods start with velocities the
// joints do not allow, so the run starts from the state projected onto them.
#include "mbsflow/graph/model.hpp"
#include "test_support.hpp"

namespace mbsflow::test {

// Six three-rod pendulums (rigid revolute chains hung from spherical pivots), neighbours
// joined tip to tip by bushings and compliant revolute joints.
inline Model pendulum_row() {
  Model m;
  m.name = "pendulum_row";
  m.gravity = {0, -9.81, 0};
  const int clusters = 6, rods = 3;
  for (int c = 0; c < clusters; ++c)
    for (int r = 0; r < rods; ++r) {
      Body b = test::make_body("rod", 1.0, {1e-3, 1.0 / 12, 1.0 / 12, 0, 0, 0}, {0.5 + r, 0, 0.4 * c});
      b.name += std::to_string(c) + "_" + std::to_string(r);
      b.velocity = {0, 0.1 * c, 0.05 * r};
      m.bodies.push_back(b);
    }
  auto joint = [&](JointType type, int a, int b, Vec3 pa, Vec3 pb) {
    Joint j;
    j.name = "j" + std::to_string(m.joints.size());
    j.type = type;
    j.body1 = a;
    j.body2 = b;
    j.point1 = pa;
    j.point2 = pb;
    j.frame2 = rest_frame2(m, j);
    m.joints.push_back(j);
    return &m.joints.back();
  };
  for (int c = 0; c < clusters; ++c) {
    const int first = c * rods;
    joint(JointType::spherical, ground, first, {0, 0, 0.4 * c}, {-0.5, 0, 0});
    for (int r = 1; r < rods; ++r) joint(JointType::revolute, first + r - 1, first + r, {0.5, 0, 0}, {-0.5, 0, 0});
    if (c == 0) continue;
    const int tip = first + rods - 1, previous = tip - rods;
    if (c % 2) {
      *joint(JointType::bushing, previous, tip, {0.5, 0, 0}, {0.5, 0, 0}) = [&] {
        Joint b = test::make_bushing(previous, tip, {0.5, 0, 0}, {0.5, 0, -0.4}, {400, 400, 400, 10, 10, 10}, {2, 2, 2, 0.1, 0.1, 0.1});
        b.name = "bushing" + std::to_string(c);
        return b;
      }();
    } else {
      Joint* j = joint(JointType::revolute, previous, tip, {0.5, 0, 0.2}, {0.5, 0, -0.2});
      j->rigid = false;
      set_bushing_from_frequency(m, *j, 30.0, 0.05);
    }
  }
  m.simulation.step = 2e-3;
  m.simulation.t_end = 0.2;
  m.simulation.output_every = 20;
  return m;
}

}  // namespace mbsflow::test
