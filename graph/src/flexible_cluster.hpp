#pragma once
// A rigid cluster that holds flexible bodies, solved in generalised velocities
// (flexible_joints.cpp): how a slot of a flexible body moves with its frame and modes,
// and the multipliers' solve. Templates on the scalar: the right-hand side runs them in
// double, its analytic Jacobian (flexible_cluster_jacobian.cpp) in dual numbers.
#include <Eigen/Cholesky>

#include "flexible_dynamics.hpp"
#include "force_laws.hpp"
#include "mbsflow/graph/flexible_body.hpp"
#include "rigid_cluster.hpp"

namespace mbsflow::flexible_cluster {

template <class T>
Matrix3T<T> cross_matrix(const Vector3T<T>& x) {
  Matrix3T<T> m;
  m << T(0.0), -x.z(), x.y(), x.z(), T(0.0), -x.x(), -x.y(), x.x(), T(0.0);
  return m;
}

// A slot of a flexible body moves by (v, w) = T xi, (a, alpha) = T xi' + gamma (world).
template <class T>
struct SlotMapT {
  Eigen::Matrix<T, 6, Eigen::Dynamic> t;
  Eigen::Matrix<T, 6, 1> gamma;
};

// Slot `node` (-1: the frame) of the flexible body d, its frame turned by r, moving with
// v_b and w (frame axes), its modes at eta, eta_rate:
//   T = [R, -R [x]x, R U_k; 0, R, R Theta_k],
//   gamma = [R (w x v_b + w x (w x x) + 2 w x U_k eta'); R (w x Theta_k eta')],
// node k at x = p_k + U_k eta (frame axes, flexible_dynamics::node_motion), small
// rotation Theta_k eta; the frame itself
// T = [R, 0, 0; 0, R, 0], gamma = [R (w x v_b); 0].
template <class T>
SlotMapT<T> slot_map(const FloatingFrameData& d, const Matrix3T<T>& r, const Vector3T<T>& v_b, const Vector3T<T>& w,
                     const flexible_dynamics::VectorT<T>& eta, const flexible_dynamics::VectorT<T>& eta_rate, int node) {
  const int ne = d.modes();
  SlotMapT<T> m{Eigen::Matrix<T, 6, Eigen::Dynamic>::Zero(6, 6 + ne), Eigen::Matrix<T, 6, 1>::Zero()};
  m.t.template block<3, 3>(0, 0) = r;
  m.t.template block<3, 3>(3, 3) = r;
  const Vector3T<T> frame_turn = w.cross(v_b);
  if (node < 0) {
    m.gamma.template head<3>() = r * frame_turn;
    return m;
  }
  const Eigen::MatrixXd& shape = d.node_shape[static_cast<std::size_t>(node)];
  const flexible_dynamics::NodeMotionT<T> n = flexible_dynamics::node_motion<T>(d, node, eta, eta_rate);
  m.t.template block<3, 3>(0, 3) = -r * cross_matrix<T>(n.position);
  m.t.block(0, 6, 3, ne) = r * as_scalar<T>(shape.topRows<3>());
  m.t.block(3, 6, 3, ne) = r * as_scalar<T>(shape.bottomRows<3>());
  m.gamma.template head<3>() =
      r * Vector3T<T>(frame_turn + w.cross(Vector3T<T>(w.cross(n.position))) + T(2.0) * w.cross(n.velocity));
  m.gamma.template tail<3>() = r * Vector3T<T>(w.cross(n.angular_velocity));
  return m;
}

// x <- S^-1 x (a vector or columns): S as it is where its Cholesky pivots show it
// regular, else shifted by eps of its diagonal and refined against it (redundant rows,
// singular positions), the policy of RigidCluster::factor.
template <class X>
void solve_rows(const Eigen::MatrixXd& s, X& x) {
  using namespace cluster_solve;
  const Eigen::LLT<Eigen::MatrixXd> plain(s);
  if (plain.info() == Eigen::Success &&
      (plain.matrixLLT().diagonal().array().square() >= regular_pivot_ratio * s.diagonal().array()).all()) {
    x = plain.solve(x);
    return;
  }
  Eigen::MatrixXd shifted = s;
  shifted.diagonal().array() += relative_shift * s.diagonal().array() + 1e-300;
  const Eigen::LDLT<Eigen::MatrixXd> factors(shifted);
  const X rhs = x;
  x = factors.solve(rhs);
  for (int k = 0; k < refinements; ++k) x += factors.solve(rhs - s * x);
}

}  // namespace mbsflow::flexible_cluster
