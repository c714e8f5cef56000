#pragma once
// FE-like matrices with a known answer for the Craig-Bampton and flexible-body tests: point
// masses (lumped, three translation DOFs each, nodes numbered 1, 2, ... in order) joined by
// axial springs of stiffness k_length / length between every two nodes at most `reach`
// apart.
#include <Eigen/Core>
#include <vector>

#include "mbsflow/analysis/craig_bampton.hpp"

namespace mbsflow::test {

struct SpringLattice {
  FeMatrices fe;
  std::vector<Eigen::Vector3d> dof_position;
};

inline SpringLattice spring_lattice(const std::vector<Eigen::Vector3d>& node, const std::vector<double>& mass, double reach,
                                    double k_length) {
  SpringLattice t;
  const auto n = static_cast<Eigen::Index>(3 * node.size());
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n), m = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t a = 0; a < node.size(); ++a) {
    for (int e = 0; e < 3; ++e) {
      t.fe.dofs.push_back({static_cast<long>(a + 1), e + 1});
      t.dof_position.push_back(node[a]);
      m(static_cast<Eigen::Index>(3 * a + e), static_cast<Eigen::Index>(3 * a + e)) = mass[a];
    }
    for (std::size_t b = a + 1; b < node.size(); ++b) {
      const Eigen::Vector3d d = node[b] - node[a];
      if (d.norm() > reach) continue;
      const Eigen::Matrix3d block = k_length / d.norm() * d.normalized() * d.normalized().transpose();
      const auto ia = static_cast<Eigen::Index>(3 * a), ib = static_cast<Eigen::Index>(3 * b);
      k.block<3, 3>(ia, ia) += block;
      k.block<3, 3>(ib, ib) += block;
      k.block<3, 3>(ia, ib) -= block;
      k.block<3, 3>(ib, ia) -= block;
    }
  }
  t.fe.stiffness = k.sparseView();
  t.fe.mass = m.sparseView();
  return t;
}

}  // namespace mbsflow::test
