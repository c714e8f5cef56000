// What a reduced part needs to move on a floating frame (flexible_body.hpp): its free
// elastic modes and the inertia invariants, from the FE model's mass matrix.
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "blas_product.hpp"
#include "mbsflow/analysis/craig_bampton.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

// The elastic modes of the reduced part (reduced coordinates x modes): the free part's
// modes but its six rigid-body motions, made mass-orthogonal to the rigid motions exactly
// (the frame's origin at the centre of mass, its axes mean axes to first order), mass-
// normalised, stiffness-diagonal. rigid: the rigid motions in reduced coordinates.
std::pair<Eigen::MatrixXd, Eigen::VectorXd> elastic_modes(const ReducedPart& part, const Eigen::MatrixXd& rigid) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> all(part.stiffness, part.mass);
  if (all.info() != Eigen::Success) throw RunError("the reduced part's free modes did not converge");
  const Eigen::Index r = part.mass.rows(), ne = r - 6;
  Eigen::MatrixXd z = all.eigenvectors().rightCols(ne);
  const Eigen::MatrixXd m_rigid = part.mass * rigid;
  z -= rigid * (rigid.transpose() * m_rigid).lu().solve(m_rigid.transpose() * z);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> sub(z.transpose() * part.stiffness * z,
                                                                      z.transpose() * part.mass * z);
  if (sub.info() != Eigen::Success) throw RunError("the reduced part's elastic modes did not converge");
  return {z * sub.eigenvectors(), sub.eigenvalues().cwiseMax(0.0)};
}

}  // namespace

FloatingFrameData floating_frame(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position, const ReducedPart& part) {
  FloatingFrameData d;
  d.mass = part.properties.mass;
  d.inertia = part.properties.inertia;
  d.centre = part.properties.centre;
  const auto n = static_cast<Eigen::Index>(fe.dofs.size()), r = part.mass.rows(), nb = static_cast<Eigen::Index>(part.interface_dofs.size());
  if (r - 6 > max_floating_modes || r <= 6) return d;  // no floating frame (reduced_part_file says why where it is asked for)
  const auto row_of = dof_rows_by_node(fe.dofs);
  const Eigen::MatrixXd rigid_fe = rigid_body_fields(fe.dofs, dof_position, d.centre);
  Eigen::MatrixXd rigid = Eigen::MatrixXd::Zero(r, 6);  // the fixed-interface modes do not move rigidly
  for (Eigen::Index k = 0; k < nb; ++k) {
    const FeDof& dof = part.interface_dofs[static_cast<std::size_t>(k)];
    rigid.row(k) = rigid_fe.row(row_of.at(dof.node)[static_cast<std::size_t>(dof.direction - 1)]);
  }
  const auto [phi, lambda] = elastic_modes(part, rigid);
  const Eigen::Index ne = phi.cols();
  d.omega2 = lambda;
  d.reduced_modes = phi;
  const Eigen::MatrixXd u = part.shapes * phi;  // the FE DOFs per elastic mode
  const Eigen::MatrixXd m_rigid = fe.mass * rigid_fe, m_u = fe.mass * u;
  d.mass0.resize(6 + ne, 6 + ne);
  d.mass0.topLeftCorner(6, 6) = transposed_product(rigid_fe, m_rigid);
  d.mass0.topRightCorner(6, ne) = transposed_product(rigid_fe, m_u);
  d.mass0.bottomLeftCorner(ne, 6) = d.mass0.topRightCorner(6, ne).transpose();
  d.mass0.bottomRightCorner(ne, ne) = transposed_product(u, m_u);
  // G_k: a translation DOF of node p along e_d moves with the frame's rotation by
  // (x_p + u_p) x e_d; per unit eta_k that changes by u_p^(k) x e_d.
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(n, 3 * ne);
  for (Eigen::Index k = 0; k < n; ++k) {
    const FeDof& dof = fe.dofs[static_cast<std::size_t>(k)];
    if (dof.direction > 3) continue;
    const auto& rows = row_of.at(dof.node);
    for (Eigen::Index mode = 0; mode < ne; ++mode) {
      Eigen::Vector3d disp = Eigen::Vector3d::Zero();
      for (int e = 0; e < 3; ++e)
        if (rows[static_cast<std::size_t>(e)] >= 0) disp[e] = u(rows[static_cast<std::size_t>(e)], mode);
      g.block<1, 3>(k, 3 * mode) = disp.cross(Eigen::Vector3d::Unit(dof.direction - 1)).transpose();
    }
  }
  const Eigen::MatrixXd m_g = fe.mass * g;
  const Eigen::MatrixXd a = transposed_product(g, m_rigid), c = transposed_product(g, m_g), e = transposed_product(g, m_u);
  for (Eigen::Index k = 0; k < ne; ++k) {
    d.a.emplace_back(a.block<3, 6>(3 * k, 0));
    d.e.emplace_back(e.block(3 * k, 0, 3, ne));
    for (Eigen::Index l = 0; l < ne; ++l) d.c.emplace_back(c.block<3, 3>(3 * k, 3 * l));
  }
  // The interface nodes: the first reduced coordinates are their DOFs, so a mode's value
  // there is its row of phi.
  for (Eigen::Index k = 0; k < nb; ++k) {
    const FeDof& dof = part.interface_dofs[static_cast<std::size_t>(k)];
    if (d.node_id.empty() || d.node_id.back() != dof.node) {
      d.node_id.push_back(dof.node);
      d.node_position.push_back(dof_position[static_cast<std::size_t>(row_of.at(dof.node)[static_cast<std::size_t>(dof.direction - 1)])] - d.centre);
      d.node_shape.push_back(Eigen::MatrixXd::Zero(6, ne));
    }
    d.node_shape.back().row(dof.direction - 1) = phi.row(k);
  }
  return d;
}

}  // namespace mbsflow
