#include "mbsflow/graph/flexible_body.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "flexible_dynamics.hpp"

namespace mbsflow {

std::vector<Eigen::Index> flexible_tail_offsets(const std::vector<FlexibleBody>& flexible) {
  std::vector<Eigen::Index> at{0};
  for (const FlexibleBody& f : flexible) at.push_back(at.back() + 2 * f.data->modes());
  return at;
}

Eigen::MatrixXd flexible_mass_matrix(const FloatingFrameData& d, const Eigen::VectorXd& eta) {
  return flexible_dynamics::mass_matrix<double>(d, eta);
}

Eigen::VectorXd flexible_accelerations(const FlexibleBody& f, const Eigen::Vector3d& v_b, const Eigen::Vector3d& w,
                                       const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const Eigen::VectorXd& q) {
  Eigen::MatrixXd m;
  const Eigen::VectorXd rhs = flexible_dynamics::balance<double>(*f.data, f.damping, v_b, w, eta, eta_rate, q, m);
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
  const flexible_dynamics::NodeMotionT<double> n = flexible_dynamics::node_motion<double>(d, node, eta, eta_rate);
  return {n.position, n.rotation, n.velocity, n.angular_velocity};
}

Eigen::Matrix3Xd flexible_surface_points(const FloatingFrameData& d, const Eigen::Vector3d& origin, const Eigen::Matrix3d& r,
                                         const Eigen::VectorXd& eta, Eigen::Matrix3Xd* elastic) {
  const Eigen::VectorXd u = d.display_shape * eta;  // part axes, point by point
  const Eigen::Matrix3Xd moved = r * Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, d.display_position.cols());
  if (elastic) *elastic = moved;
  return (r * d.display_position + moved).colwise() + origin;
}

}  // namespace mbsflow
