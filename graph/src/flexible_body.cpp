#include "mbsflow/graph/flexible_body.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace mbsflow {
namespace {

// d M / d eta_k's rotation block: A_k's rotation columns twice (symmetrised) and the
// quadratic invariants against eta.
Eigen::Matrix3d rotation_block_rate(const FloatingFrameData& d, int k, const Eigen::VectorXd& eta) {
  const int ne = d.modes();
  Eigen::Matrix3d s = d.a[static_cast<std::size_t>(k)].rightCols<3>();
  s += s.transpose().eval();
  for (int l = 0; l < ne; ++l)
    s += eta[l] * (d.c[static_cast<std::size_t>(k * ne + l)] + d.c[static_cast<std::size_t>(l * ne + k)]);
  return s;
}

}  // namespace

std::vector<Eigen::Index> flexible_tail_offsets(const std::vector<FlexibleBody>& flexible) {
  std::vector<Eigen::Index> at{0};
  for (const FlexibleBody& f : flexible) at.push_back(at.back() + 2 * f.data->modes());
  return at;
}

Eigen::MatrixXd flexible_mass_matrix(const FloatingFrameData& d, const Eigen::VectorXd& eta) {
  const int ne = d.modes();
  Eigen::MatrixXd m = d.mass0;
  Eigen::Matrix3d rr = Eigen::Matrix3d::Zero();
  for (int k = 0; k < ne; ++k) {
    const auto& a = d.a[static_cast<std::size_t>(k)];
    m.block<3, 3>(3, 0) += eta[k] * a.leftCols<3>();
    m.block<3, 3>(0, 3) += eta[k] * a.leftCols<3>().transpose();
    rr += eta[k] * (a.rightCols<3>() + a.rightCols<3>().transpose());
    m.block(3, 6, 3, ne) += eta[k] * d.e[static_cast<std::size_t>(k)];
    m.block(6, 3, ne, 3) += eta[k] * d.e[static_cast<std::size_t>(k)].transpose();
    for (int l = 0; l < ne; ++l) rr += eta[k] * eta[l] * d.c[static_cast<std::size_t>(k * ne + l)];
  }
  m.block<3, 3>(3, 3) += rr;
  return m;
}

Eigen::VectorXd flexible_accelerations(const FlexibleBody& f, const Eigen::Vector3d& v_b, const Eigen::Vector3d& w,
                                       const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const Eigen::VectorXd& q) {
  const FloatingFrameData& d = *f.data;
  const int ne = d.modes();
  Eigen::VectorXd xi(6 + ne);
  xi << v_b, w, eta_rate;
  const Eigen::MatrixXd m = flexible_mass_matrix(d, eta);
  const Eigen::VectorXd p = m * xi;
  Eigen::VectorXd rhs = q;
  // Lagrange's d/dt (dT/d xi) - dT/d eta in the frame's quasi-velocities.
  rhs.head<3>() -= w.cross(p.head<3>());
  rhs.segment<3>(3) -= w.cross(p.segment<3>(3)) + v_b.cross(p.head<3>());
  for (int k = 0; k < ne; ++k) {
    const auto& a = d.a[static_cast<std::size_t>(k)];
    const auto& e = d.e[static_cast<std::size_t>(k)];
    Eigen::VectorXd mk_xi = Eigen::VectorXd::Zero(6 + ne);  // d M / d eta_k xi
    mk_xi.head<3>() = a.leftCols<3>().transpose() * w;
    mk_xi.segment<3>(3) = a.leftCols<3>() * v_b + rotation_block_rate(d, k, eta) * w + e * eta_rate;
    mk_xi.tail(ne) = e.transpose() * w;
    rhs -= eta_rate[k] * mk_xi;                // -M' xi
    rhs[6 + k] += 0.5 * xi.dot(mk_xi);         // + dT / d eta_k
  }
  rhs.tail(ne) -= d.omega2.cwiseProduct(eta) + f.damping.cwiseProduct(eta_rate);
  return m.ldlt().solve(rhs);
}

double flexible_kinetic_energy(const FloatingFrameData& d, const Eigen::Vector3d& v_b, const Eigen::Vector3d& w,
                               const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate) {
  Eigen::VectorXd xi(6 + d.modes());
  xi << v_b, w, eta_rate;
  return 0.5 * xi.dot(flexible_mass_matrix(d, eta) * xi);
}

double flexible_strain_energy(const FloatingFrameData& d, const Eigen::VectorXd& eta) {
  return 0.5 * eta.dot(d.omega2.cwiseProduct(eta));
}

NodeMotion flexible_node_motion(const FloatingFrameData& d, int node, const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate) {
  const Eigen::MatrixXd& s = d.node_shape[static_cast<std::size_t>(node)];
  NodeMotion n;
  n.position = d.node_position[static_cast<std::size_t>(node)] + s.topRows<3>() * eta;
  n.rotation = s.bottomRows<3>() * eta;
  n.velocity = s.topRows<3>() * eta_rate;
  n.angular_velocity = s.bottomRows<3>() * eta_rate;
  return n;
}

Eigen::Matrix3Xd flexible_surface_points(const FloatingFrameData& d, const Eigen::Vector3d& origin, const Eigen::Matrix3d& r,
                                         const Eigen::VectorXd& eta, Eigen::Matrix3Xd* elastic) {
  const Eigen::VectorXd u = d.display_shape * eta;  // part axes, point by point
  const Eigen::Matrix3Xd moved = r * Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, d.display_position.cols());
  if (elastic) *elastic = moved;
  return (r * d.display_position + moved).colwise() + origin;
}

}  // namespace mbsflow
