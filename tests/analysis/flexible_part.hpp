#pragma once
// The flexible-body tests' part: a bar-like spring lattice reduced by Craig-Bampton, and a
// model of it alone as the model reader makes it.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "mbsflow/analysis/craig_bampton.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "spring_lattice.hpp"

namespace mbsflow::test {

// Nodes on a 6 x 2 x 2 grid (0.2 m along x, 0.1 m across), 0.5 .. 1.5 kg each, springs of
// stiffness / length N/m between nodes at most a cell's diagonal apart (bar_lattice),
// reduced at `interface`: nodes 1-4 are the end x = 0, 21-24 the end x = 1.
inline SpringLattice bar_lattice(double stiffness = 2e5) {
  std::vector<Eigen::Vector3d> node;
  std::vector<double> mass;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) {
        node.emplace_back(0.2 * i, 0.1 * j, 0.1 * k + 0.01 * i);
        mass.push_back(0.5 + 0.1 * static_cast<double>(node.size() % 11));
      }
  return spring_lattice(node, mass, 0.26, stiffness);
}

inline ReducedPart bar_part(int modes, std::vector<long> interface = {1, 2, 3, 4}, double stiffness = 2e5) {
  const SpringLattice lattice = bar_lattice(stiffness);
  CraigBamptonOptions o;
  o.interface_nodes = std::move(interface);
  o.modes = modes;
  return craig_bampton(lattice.fe, lattice.dof_position, o);
}

// A model of the part alone (frame at the origin, unturned), as the model reader makes it:
// the frame body, then a body per interface node.
inline Model flexible_model(const ReducedPart& part) {
  Model m;
  FlexibleBody f;
  f.name = "bar";
  f.data = std::make_shared<const FloatingFrameData>(part.floating);
  const FloatingFrameData& d = *f.data;
  f.damping = Eigen::VectorXd::Zero(d.modes());
  auto add = [&](const std::string& name, double mass, const Eigen::Matrix3d& j, const Eigen::Vector3d& x) {
    Body b;
    b.name = name;
    b.mass = mass;
    b.inertia = Vec6{j(0, 0), j(1, 1), j(2, 2), j(0, 1), j(0, 2), j(1, 2)};
    b.position = {x.x(), x.y(), x.z()};
    m.bodies.push_back(b);
    return static_cast<int>(m.bodies.size()) - 1;
  };
  f.frame = add("bar", d.mass, d.inertia, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < d.node_id.size(); ++k)
    f.nodes.push_back(add("bar@" + std::to_string(d.node_id[k]), d.mass / 4, d.inertia / 4, d.node_position[k]));
  m.flexible.push_back(std::move(f));
  return m;
}

// The model of two parts: b's bodies after a's, b's flexible body after a's.
inline Model joined_models(Model a, const Model& b) {
  const int offset = static_cast<int>(a.bodies.size());
  a.bodies.insert(a.bodies.end(), b.bodies.begin(), b.bodies.end());
  for (FlexibleBody f : b.flexible) {
    f.frame += offset;
    for (int& n : f.nodes) n += offset;
    a.flexible.push_back(std::move(f));
  }
  return a;
}

// Flexible body `which`'s momentum and angular momentum about the world origin (world
// axes) at y, from its mass matrix M(eta) and its generalised velocities.
struct Momentum {
  Eigen::Vector3d linear, angular;
};

inline Momentum flexible_momentum(const MultibodySystem& sys, const Eigen::VectorXd& y, std::size_t which = 0) {
  const StateLayout& l = sys.layout();
  const FlexibleBody& f = sys.model().flexible[which];
  const int ne = f.data->modes();
  const Eigen::Vector4d q = y.segment<4>(l.orientation(f.frame));
  const Eigen::Matrix3d r = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Eigen::Index tail = sys.flexible_state(which);
  const Eigen::VectorXd eta = y.segment(tail, ne);
  Eigen::VectorXd xi(6 + ne);
  xi << r.transpose() * y.segment<3>(l.velocity(f.frame)), y.segment<3>(l.angular_velocity(f.frame)), y.segment(tail + ne, ne);
  const Eigen::VectorXd p = flexible_mass_matrix(*f.data, eta) * xi;
  const Eigen::Vector3d linear = r * p.head<3>();
  return {linear, Eigen::Vector3d(y.segment<3>(l.position(f.frame))).cross(linear) + r * p.segment<3>(3)};
}

}  // namespace mbsflow::test
