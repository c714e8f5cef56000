#pragma once
// A flexible body's equations of motion (flexible_body.hpp) as templates on the scalar:
// the right-hand side runs them in double, the analytic Jacobian (flexible_jacobian.cpp)
// in dual numbers, so both differentiate one arithmetic.
#include <Eigen/Core>
#include <type_traits>
#include <vector>

#include "force_laws.hpp"
#include "mbsflow/graph/flexible_body.hpp"
#include "rotation.hpp"

namespace mbsflow::flexible_dynamics {

template <class T>
using VectorT = Eigen::Matrix<T, Eigen::Dynamic, 1>;
template <class T>
using MatrixT = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

// The values of dual numbers, or doubles as they are.
template <class T>
Eigen::VectorXd values_of(const VectorT<T>& x) {
  if constexpr (std::is_same_v<T, double>) {
    return x;
  } else {
    Eigen::VectorXd v(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) v[i] = x[i].value();
    return v;
  }
}

// A dual number for a function of eta alone, by the chain rule: its value, and its
// derivatives sum_k slope(k) d(eta_k). The inertia terms of M(eta) are quadratic in eta:
// their arithmetic in dual numbers took ne^2 products of whole derivative vectors.
template <class T, class Slope>
T through_eta(double value, const VectorT<T>& eta, Slope&& slope) {
  typename T::DerType der;
  bool any = false;
  for (Eigen::Index k = 0; k < eta.size(); ++k) {
    const double s = slope(static_cast<int>(k));
    if (s == 0.0 || eta[k].derivatives().size() == 0) continue;
    if (!any) der = s * eta[k].derivatives();
    else der += s * eta[k].derivatives();
    any = true;
  }
  return any ? T(value, der) : T(value);
}

// d M / d eta_k's rotation block: A_k's rotation columns twice (symmetrised) and the
// quadratic invariants against eta.
template <class T>
Matrix3T<T> rotation_block_rate(const FloatingFrameData& d, int k, const VectorT<T>& eta) {
  const int ne = d.modes();
  if constexpr (!std::is_same_v<T, double>) {  // linear in eta: d / d eta_l = C_kl + C_lk
    const Eigen::Matrix3d value = rotation_block_rate<double>(d, k, values_of(eta));
    Matrix3T<T> s;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        s(i, j) = through_eta<T>(value(i, j), eta, [&](int l) {
          return d.c[static_cast<std::size_t>(k * ne + l)](i, j) + d.c[static_cast<std::size_t>(l * ne + k)](i, j);
        });
    return s;
  }
  Eigen::Matrix3d twice = d.a[static_cast<std::size_t>(k)].rightCols<3>();
  twice += twice.transpose().eval();
  Matrix3T<T> s = as_scalar<T>(twice);
  for (int l = 0; l < ne; ++l)
    s += eta[l] * as_scalar<T>(d.c[static_cast<std::size_t>(k * ne + l)] + d.c[static_cast<std::size_t>(l * ne + k)]);
  return s;
}

// M(eta), (6 + ne)^2.
template <class T>
MatrixT<T> mass_matrix(const FloatingFrameData& d, const VectorT<T>& eta) {
  const int ne = d.modes();
  if constexpr (!std::is_same_v<T, double>) {  // its value, and d M / d eta_k by the chain rule
    const Eigen::VectorXd at = values_of(eta);
    const Eigen::MatrixXd value = mass_matrix<double>(d, at);
    std::vector<Eigen::MatrixXd> slope(static_cast<std::size_t>(ne), Eigen::MatrixXd::Zero(6 + ne, 6 + ne));
    for (int k = 0; k < ne; ++k) {
      const Eigen::Matrix<double, 3, 6>& a = d.a[static_cast<std::size_t>(k)];
      const Eigen::MatrixXd& e = d.e[static_cast<std::size_t>(k)];
      Eigen::MatrixXd& s = slope[static_cast<std::size_t>(k)];
      s.block<3, 3>(3, 0) = a.leftCols<3>();
      s.block<3, 3>(0, 3) = a.leftCols<3>().transpose();
      s.block<3, 3>(3, 3) = rotation_block_rate<double>(d, k, at);
      s.block(3, 6, 3, ne) = e;
      s.block(6, 3, ne, 3) = e.transpose();
    }
    MatrixT<T> m = value.template cast<T>();
    for (int i = 0; i < 6 + ne; ++i)
      for (int j = 0; j < 6 + ne; ++j)
        if ((i >= 3 && i < 6) || (j >= 3 && j < 6))  // the rest is constant
          m(i, j) = through_eta<T>(value(i, j), eta, [&](int k) { return slope[static_cast<std::size_t>(k)](i, j); });
    return m;
  }
  MatrixT<T> m = as_scalar<T>(d.mass0);
  Matrix3T<T> rr = Matrix3T<T>::Zero();
  for (int k = 0; k < ne; ++k) {
    const Eigen::Matrix<double, 3, 6>& a = d.a[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd& e = d.e[static_cast<std::size_t>(k)];
    m.template block<3, 3>(3, 0) += eta[k] * as_scalar<T>(a.leftCols<3>());
    m.template block<3, 3>(0, 3) += eta[k] * as_scalar<T>(a.leftCols<3>().transpose());
    rr += eta[k] * as_scalar<T>(a.rightCols<3>() + a.rightCols<3>().transpose());
    m.block(3, 6, 3, ne) += eta[k] * as_scalar<T>(e);
    m.block(6, 3, ne, 3) += eta[k] * as_scalar<T>(e.transpose());
    for (int l = 0; l < ne; ++l) rr += eta[k] * eta[l] * as_scalar<T>(d.c[static_cast<std::size_t>(k * ne + l)]);
  }
  m.template block<3, 3>(3, 3) += rr;
  return m;
}

// The right side of M(eta) xi' = Q + Q_v - K eta - D eta' (M into *m): Lagrange's
// d/dt (dT/d xi) - dT/d eta in the frame's quasi-velocities xi = [v_b, w, eta'], with the
// applied generalised force q.
template <class T>
VectorT<T> balance(const FloatingFrameData& d, const Eigen::VectorXd& damping, const Vector3T<T>& v_b, const Vector3T<T>& w,
                   const VectorT<T>& eta, const VectorT<T>& eta_rate, const VectorT<T>& q, MatrixT<T>& m) {
  const int ne = d.modes();
  VectorT<T> xi(6 + ne);
  xi << v_b, w, eta_rate;
  m = mass_matrix<T>(d, eta);
  const VectorT<T> p = m * xi;
  VectorT<T> rhs = q;
  rhs.template head<3>() -= w.cross(Vector3T<T>(p.template head<3>()));
  rhs.template segment<3>(3) -= w.cross(Vector3T<T>(p.template segment<3>(3))) + v_b.cross(Vector3T<T>(p.template head<3>()));
  for (int k = 0; k < ne; ++k) {
    const Eigen::Matrix<double, 3, 6>& a = d.a[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd& e = d.e[static_cast<std::size_t>(k)];
    VectorT<T> mk_xi = VectorT<T>::Zero(6 + ne);  // d M / d eta_k xi
    mk_xi.template head<3>() = as_scalar<T>(a.leftCols<3>().transpose()) * w;
    mk_xi.template segment<3>(3) = as_scalar<T>(a.leftCols<3>()) * v_b + rotation_block_rate<T>(d, k, eta) * w + as_scalar<T>(e) * eta_rate;
    mk_xi.tail(ne) = as_scalar<T>(e.transpose()) * w;
    rhs -= eta_rate[k] * mk_xi;         // -M' xi
    rhs[6 + k] += 0.5 * xi.dot(mk_xi);  // + dT / d eta_k
  }
  rhs.tail(ne) -= as_scalar<T>(d.omega2).cwiseProduct(eta) + as_scalar<T>(damping).cwiseProduct(eta_rate);
  return rhs;
}

// The applied generalised force (6 + ne): the frame's wrench (world axes, about its
// origin; wrench_at(-1, force, torque)) and gravity on the part's mass at its origin
// already in it, gravity's share on the deformation (the centre of mass moves with the
// modes by L eta), and node k's wrench (wrench_at(k, ...)) through its motion.
template <class T, class WrenchAt>
VectorT<T> generalised_force(const FloatingFrameData& d, const Matrix3T<T>& r, const Eigen::Vector3d& gravity, const VectorT<T>& eta,
                             WrenchAt&& wrench_at) {
  const int ne = d.modes();
  VectorT<T> q = VectorT<T>::Zero(6 + ne);
  Vector3T<T> force, torque;
  wrench_at(-1, force, torque);
  const Matrix3T<T> rt = r.transpose();
  q.template head<3>() = rt * force;
  q.template segment<3>(3) = rt * torque;
  const Vector3T<T> g_b = rt * as_scalar<T>(gravity);
  const auto l = d.mass0.block(0, 6, 3, ne);
  q.template segment<3>(3) += Vector3T<T>(as_scalar<T>(l) * eta).cross(g_b);
  q.tail(ne) += as_scalar<T>(l.transpose()) * g_b;
  for (std::size_t k = 0; k < d.node_shape.size(); ++k) {
    wrench_at(static_cast<int>(k), force, torque);
    const Vector3T<T> f_b = rt * force, t_b = rt * torque;
    const Eigen::MatrixXd& shape = d.node_shape[k];
    const Vector3T<T> arm = as_scalar<T>(d.node_position[k]) + as_scalar<T>(shape.topRows<3>()) * eta;
    q.template head<3>() += f_b;
    q.template segment<3>(3) += arm.cross(f_b) + t_b;
    q.tail(ne) += as_scalar<T>(shape.topRows<3>().transpose()) * f_b + as_scalar<T>(shape.bottomRows<3>().transpose()) * t_b;
  }
  return q;
}

// Node k's place and small rotation in the frame (body axes, from the origin) and their
// rates, at eta, eta' (flexible_node_motion in double).
template <class T>
struct NodeMotionT {
  Vector3T<T> position, rotation, velocity, angular_velocity;
};
template <class T>
NodeMotionT<T> node_motion(const FloatingFrameData& d, int k, const VectorT<T>& eta, const VectorT<T>& eta_rate) {
  const Eigen::MatrixXd& s = d.node_shape[static_cast<std::size_t>(k)];
  return {as_scalar<T>(d.node_position[static_cast<std::size_t>(k)]) + as_scalar<T>(s.topRows<3>()) * eta,
          as_scalar<T>(s.bottomRows<3>()) * eta, as_scalar<T>(s.topRows<3>()) * eta_rate, as_scalar<T>(s.bottomRows<3>()) * eta_rate};
}

// Node k's world motion from the frame's (position, velocity, quaternion, its rotation r,
// angular velocity w in body axes) and the modes.
template <class T>
struct NodeWorldT {
  Vector3T<T> position, velocity, omega;  // omega: world axes
  Vector4T<T> quat;
};
template <class T>
NodeWorldT<T> node_world(const FloatingFrameData& d, int k, const VectorT<T>& eta, const VectorT<T>& eta_rate, const Vector3T<T>& pos,
                         const Vector3T<T>& vel, const Vector4T<T>& quat, const Matrix3T<T>& r, const Vector3T<T>& w) {
  const NodeMotionT<T> n = node_motion<T>(d, k, eta, eta_rate);
  return {pos + r * n.position, vel + r * Vector3T<T>(w.cross(n.position) + n.velocity), r * Vector3T<T>(w + n.angular_velocity),
          quat_multiply<T>(quat, quat_exp<T>(n.rotation))};
}

}  // namespace mbsflow::flexible_dynamics
