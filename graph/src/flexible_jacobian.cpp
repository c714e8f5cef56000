#include "flexible_jacobian.hpp"

#include <Eigen/Cholesky>
#include <unsupported/Eigen/AutoDiff>

#include "flexible_dynamics.hpp"

namespace mbsflow::flexible_jacobian {
namespace {

using jacobian_seeds::HeapDual;
using jacobian_seeds::put_rows;
using jacobian_seeds::stack_variables;
using jacobian_seeds::StackDual;
using flexible_dynamics::VectorT;

template <class Dual>
Eigen::MatrixXd node_map_in(const FloatingFrameData& d, int k, const BodyNumbers& frame, const Eigen::VectorXd& eta,
                            const Eigen::VectorXd& eta_rate) {
  const int variables = 13 + 2 * d.modes();
  const jacobian_seeds::SeededModes<Dual> s = jacobian_seeds::seeded_modes<Dual>(frame, eta, eta_rate, 0, variables);
  const Matrix3T<Dual> r = rotation_matrix<Dual>(s.q);
  const flexible_dynamics::NodeWorldT<Dual> n = flexible_dynamics::node_world<Dual>(d, k, s.eta, s.eta_rate, s.r, s.v, s.q, r, s.w);
  const Vector3T<Dual> w_body = rotation_matrix<Dual>(n.quat).transpose() * n.omega;
  Eigen::MatrixXd out(13, variables);
  put_rows(n.position, 0, variables, out);
  put_rows(n.quat, 3, variables, out);
  put_rows(n.velocity, 7, variables, out);
  put_rows(w_body, 10, variables, out);
  return out;
}

template <class Dual>
Eigen::MatrixXd rate_derivatives_in(const FlexibleBody& fb, const Eigen::Vector3d& gravity, const BodyNumbers& frame,
                                    const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const std::vector<SlotWrench>& wrench,
                                    int variables) {
  const FloatingFrameData& d = *fb.data;
  const int ne = d.modes();
  const jacobian_seeds::SeededModes<Dual> s = jacobian_seeds::seeded_modes<Dual>(frame, eta, eta_rate, 0, variables);
  const Matrix3T<Dual> r = rotation_matrix<Dual>(s.q);
  const VectorT<Dual> q = flexible_dynamics::generalised_force<Dual>(d, r, gravity, s.eta, [&](int k, Vector3T<Dual>& force, Vector3T<Dual>& torque) {
    const SlotWrench& at = wrench[static_cast<std::size_t>(k + 1)];
    for (int c = 0; c < 3; ++c) {
      force[c] = Dual(at.value[c], at.derivatives.row(c).transpose());
      torque[c] = Dual(at.value[3 + c], at.derivatives.row(3 + c).transpose());
    }
  });
  const Vector3T<Dual> v_b = r.transpose() * s.v;
  flexible_dynamics::MatrixT<Dual> m;
  const VectorT<Dual> rhs = flexible_dynamics::balance<Dual>(d, fb.damping, v_b, s.w, s.eta, s.eta_rate, q, m);
  // xi' = M^-1 rhs: its value by the factor of M's values, its derivatives from
  // M d xi' = d rhs - (d M) xi', the right side being the derivatives of rhs - M xi'.
  const int size = 6 + ne;
  Eigen::MatrixXd m_value(size, size);
  Eigen::VectorXd rhs_value(size);
  for (int i = 0; i < size; ++i) {
    rhs_value[i] = rhs[i].value();
    for (int j = 0; j < size; ++j) m_value(i, j) = m(i, j).value();
  }
  const Eigen::LDLT<Eigen::MatrixXd> factor(m_value);
  const Eigen::VectorXd xi_value = factor.solve(rhs_value);
  const VectorT<Dual> residual = rhs - m * xi_value.cast<Dual>();
  Eigen::MatrixXd d_residual(size, variables);
  put_rows(residual, 0, variables, d_residual);
  const Eigen::MatrixXd d_xi = factor.solve(d_residual);
  VectorT<Dual> xi_rate(size);
  for (int i = 0; i < size; ++i) xi_rate[i] = Dual(xi_value[i], d_xi.row(i).transpose());
  // The frame's rates as write_flexible_rates gives them.
  const Vector4T<Dual> q_rate = quaternion_rate<Dual>(s.q, s.w);
  const Vector3T<Dual> v_rate = r * Vector3T<Dual>(Vector3T<Dual>(xi_rate.template head<3>()) + s.w.cross(v_b));
  Eigen::MatrixXd out(10 + ne, variables);
  put_rows(q_rate, 0, variables, out);
  put_rows(v_rate, 4, variables, out);
  out.middleRows(7, 3) = d_xi.middleRows(3, 3);
  out.bottomRows(ne) = d_xi.bottomRows(ne);
  return out;
}

}  // namespace

Eigen::MatrixXd node_map(const FloatingFrameData& d, int k, const BodyNumbers& frame, const Eigen::VectorXd& eta,
                         const Eigen::VectorXd& eta_rate) {
  if (13 + 2 * d.modes() <= stack_variables) return node_map_in<StackDual>(d, k, frame, eta, eta_rate);
  return node_map_in<HeapDual>(d, k, frame, eta, eta_rate);
}

Eigen::MatrixXd rate_derivatives(const FlexibleBody& fb, const Eigen::Vector3d& gravity, const BodyNumbers& frame,
                                 const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const std::vector<SlotWrench>& wrench,
                                 int variables) {
  if (variables <= stack_variables) return rate_derivatives_in<StackDual>(fb, gravity, frame, eta, eta_rate, wrench, variables);
  return rate_derivatives_in<HeapDual>(fb, gravity, frame, eta, eta_rate, wrench, variables);
}

}  // namespace mbsflow::flexible_jacobian
