#include "mbsflow/analysis/linearization.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

Eigen::Matrix3d rotation(const Eigen::VectorXd& y, const StateLayout& l, int b) {
  const auto q = y.segment<4>(l.orientation(b));
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

// dq = H dphi / 2 for q = exp(phi) q0 (world-frame rotation vector), H^T H = I.
Eigen::Matrix<double, 4, 3> half_map(const Eigen::Vector4d& q) {
  const Eigen::Vector3d qv = q.tail<3>();
  Eigen::Matrix<double, 4, 3> h;
  h.row(0) = -qv.transpose();
  h.bottomRows<3>() = q[0] * Eigen::Matrix3d::Identity() - skew(qv);
  return h;
}

Eigen::Matrix3d body_inertia(const Body& b) { return inertia_matrix(b.inertia.get()); }

// T: tangent (x, v) of the free bodies -> the state's numbers; T+: its left inverse.
void tangent_maps(const StateLayout& l, const std::vector<int>& bodies, const Eigen::VectorXd& y,
                  Eigen::SparseMatrix<double>& t, Eigen::SparseMatrix<double>& t_plus) {
  const auto n = static_cast<Eigen::Index>(bodies.size());
  Triplets a, b;
  for (Eigen::Index k = 0; k < n; ++k) {
    const int body = bodies[static_cast<std::size_t>(k)];
    const Eigen::Index x = 6 * k, v = 6 * n + 6 * k;
    const Eigen::Index P = l.position(body), Q = l.orientation(body), V = l.velocity(body), W = l.angular_velocity(body);
    const Eigen::Vector4d q = y.segment<4>(Q).normalized();
    const Eigen::Matrix3d R = rotation(y, l, body);
    const Eigen::Vector3d omega = R * y.segment<3>(W);
    const Eigen::Matrix<double, 4, 3> h = half_map(q);
    const Eigen::Matrix<double, 3, 4> g_plus = 2.0 * h.transpose();
    const Eigen::Matrix3d rt_omega = R.transpose() * skew(omega);
    const Eigen::Matrix<double, 3, 4> omega_g = -skew(omega) * g_plus;
    for (int i = 0; i < 3; ++i) {
      a.emplace_back(P + i, x + i, 1.0);
      a.emplace_back(V + i, v + i, 1.0);
      b.emplace_back(x + i, P + i, 1.0);
      b.emplace_back(v + i, V + i, 1.0);
      for (int c = 0; c < 3; ++c) {
        a.emplace_back(W + i, v + 3 + c, R(c, i));  // w = R^T omega
        a.emplace_back(W + i, x + 3 + c, rt_omega(i, c));
        b.emplace_back(v + 3 + c, W + i, R(c, i));
      }
    }
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 3; ++c) {
        a.emplace_back(Q + r, x + 3 + c, 0.5 * h(r, c));
        b.emplace_back(x + 3 + c, Q + r, g_plus(c, r));
        b.emplace_back(v + 3 + c, Q + r, omega_g(c, r));
      }
  }
  t.resize(l.size(), 12 * n);
  t.setFromTriplets(a.begin(), a.end());
  t_plus.resize(12 * n, l.size());
  t_plus.setFromTriplets(b.begin(), b.end());
}

// The state moved by h along tangent direction `column` (0 .. 12 n).
Eigen::VectorXd moved(const StateLayout& l, const std::vector<int>& bodies, const Eigen::VectorXd& y, Eigen::Index column,
                      double h) {
  const auto n = static_cast<Eigen::Index>(bodies.size());
  Eigen::VectorXd out = y;
  const bool rate = column >= 6 * n;
  const Eigen::Index local = rate ? column - 6 * n : column;
  const int body = bodies[static_cast<std::size_t>(local / 6)];
  const int c = static_cast<int>(local % 6);
  if (!rate && c < 3) {
    out[l.position(body) + c] += h;
  } else if (!rate) {
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    axis[c - 3] = 1.0;
    const auto q = y.segment<4>(l.orientation(body));
    const Eigen::Quaterniond turned = Eigen::Quaterniond(Eigen::AngleAxisd(h, axis)) *
                                      Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    out.segment<4>(l.orientation(body)) << turned.w(), turned.x(), turned.y(), turned.z();
    // The world-frame angular velocity stays: the body-frame one turns with the body.
    const Eigen::Vector3d omega = rotation(y, l, body) * y.segment<3>(l.angular_velocity(body));
    out.segment<3>(l.angular_velocity(body)) = turned.toRotationMatrix().transpose() * omega;
  } else if (c < 3) {
    out[l.velocity(body) + c] += h;
  } else {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[c - 3] = h;
    out.segment<3>(l.angular_velocity(body)) += rotation(y, l, body).transpose() * d;
  }
  return out;
}

// J T: the state derivative's change along each tangent direction, by central differences.
Eigen::SparseMatrix<double> differenced(MultibodySystem& sys, double t, const Eigen::VectorXd& y,
                                        const std::vector<int>& bodies) {
  const StateLayout& l = sys.layout();
  const Eigen::Index columns = 12 * static_cast<Eigen::Index>(bodies.size());
  Eigen::VectorXd plus(l.size()), minus(l.size());
  Triplets out;
  for (Eigen::Index c = 0; c < columns; ++c) {
    const double h = 1e-6;
    sys.rhs(t, moved(l, bodies, y, c, h), plus);
    sys.rhs(t, moved(l, bodies, y, c, -h), minus);
    for (Eigen::Index r = 0; r < l.size(); ++r)
      if (const double d = (plus[r] - minus[r]) / (2.0 * h); d != 0.0) out.emplace_back(r, c, d);
  }
  Eigen::SparseMatrix<double> jt(l.size(), columns);
  jt.setFromTriplets(out.begin(), out.end());
  return jt;
}

// The mass matrix's block of body b: m I on the translation, the world-frame inertia on the rotation.
Eigen::Matrix<double, 6, 6> mass_block(const Body& body, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  m.topLeftCorner<3, 3>() = body.mass * Eigen::Matrix3d::Identity();
  m.bottomRightCorner<3, 3>() = R * body_inertia(body) * R.transpose();
  return m;
}

// K = -M A_vx and D = -M A_vv straight from the state Jacobian, body pair by body pair:
// A's rate rows of body r and tangent columns of body c are L_r J_rc T_c, where J_rc holds
// J's rows (orientation, velocity, angular velocity) of r and columns (all 13) of c, L_r is
// the tangent map's rate rows and T_c its columns. Equal to the products tp J tm of the
// general path without forming them (which took most of an equilibrium iteration on large
// models); every entry of a coupled pair is kept, so the pattern follows J's alone.
void rate_blocks(const StateLayout& l, const std::vector<int>& bodies, const Eigen::VectorXd& y,
                 const Eigen::SparseMatrix<double>& jac, const std::vector<Eigen::Matrix<double, 6, 6>>& mass,
                 Triplets& k_out, Triplets& d_out) {
  const Eigen::Index nb = l.bodies;
  std::vector<int> index_of(static_cast<std::size_t>(nb), -1);  // system body -> free index
  for (std::size_t k = 0; k < bodies.size(); ++k) index_of[static_cast<std::size_t>(bodies[k])] = static_cast<int>(k);
  using Left = Eigen::Matrix<double, 6, 10>;
  using Right = Eigen::Matrix<double, 13, 12>;
  std::vector<Left> left(bodies.size());
  std::vector<Right> right(bodies.size());
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const int b = bodies[k];
    const Eigen::Vector4d q = y.segment<4>(l.orientation(b)).normalized();
    const Eigen::Matrix3d R = rotation(y, l, b);
    const Eigen::Vector3d omega = R * y.segment<3>(l.angular_velocity(b));
    const Eigen::Matrix<double, 4, 3> h = half_map(q);
    Left& L = left[k];  // rows: v (3), omega (3); columns: q (4), v (3), w (3) of the state
    L.setZero();
    L.block<3, 3>(0, 4).setIdentity();
    L.block<3, 4>(3, 0) = -skew(omega) * (2.0 * h.transpose());
    L.block<3, 3>(3, 7) = R;
    Right& T = right[k];  // rows: p, q, v, w of the state; columns: x (3 + 3), v (3 + 3)
    T.setZero();
    T.block<3, 3>(0, 0).setIdentity();
    T.block<4, 3>(3, 3) = 0.5 * h;
    T.block<3, 3>(7, 6).setIdentity();
    T.block<3, 3>(10, 3) = R.transpose() * skew(omega);
    T.block<3, 3>(10, 9) = R.transpose();
  }
  // Where row s of the state lies: body, and row in J_rc (-1: a position row, not needed).
  const auto locate_row = [&](Eigen::Index s, Eigen::Index& body) -> int {
    if (s < 3 * nb) return -1;
    if (s < 7 * nb) return body = (s - 3 * nb) / 4, static_cast<int>((s - 3 * nb) % 4);
    if (s < 10 * nb) return body = (s - 7 * nb) / 3, 4 + static_cast<int>((s - 7 * nb) % 3);
    return body = (s - 10 * nb) / 3, 7 + static_cast<int>((s - 10 * nb) % 3);
  };
  std::vector<int> slot(bodies.size(), -1);
  std::vector<int> rows_of;  // the free bodies coupled to column body c
  std::vector<Eigen::Matrix<double, 10, 13>> blocks;
  for (std::size_t c = 0; c < bodies.size(); ++c) {
    const int b = bodies[c];
    rows_of.clear();
    const Eigen::Index columns[13] = {l.position(b),        l.position(b) + 1,    l.position(b) + 2,    l.orientation(b),
                                      l.orientation(b) + 1, l.orientation(b) + 2, l.orientation(b) + 3, l.velocity(b),
                                      l.velocity(b) + 1,    l.velocity(b) + 2,    l.angular_velocity(b),
                                      l.angular_velocity(b) + 1, l.angular_velocity(b) + 2};
    for (int j = 0; j < 13; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(jac, columns[j]); it; ++it) {
        Eigen::Index body = 0;
        const int row = locate_row(it.row(), body);
        if (row < 0) continue;
        const int r = index_of[static_cast<std::size_t>(body)];
        if (r < 0) continue;  // a driven body's rows: no coordinates
        if (slot[static_cast<std::size_t>(r)] < 0) {
          slot[static_cast<std::size_t>(r)] = static_cast<int>(rows_of.size());
          rows_of.push_back(r);
          if (blocks.size() < rows_of.size()) blocks.emplace_back();
          blocks[rows_of.size() - 1].setZero();
        }
        blocks[static_cast<std::size_t>(slot[static_cast<std::size_t>(r)])](row, j) = it.value();
      }
    for (std::size_t i = 0; i < rows_of.size(); ++i) {
      const auto r = static_cast<std::size_t>(rows_of[i]);
      const Eigen::Matrix<double, 6, 12> a = -mass[r] * (left[r] * blocks[i] * right[c]);
      for (int row = 0; row < 6; ++row)
        for (int col = 0; col < 6; ++col) {
          k_out.emplace_back(static_cast<int>(6 * r) + row, static_cast<int>(6 * c) + col, a(row, col));
          d_out.emplace_back(static_cast<int>(6 * r) + row, static_cast<int>(6 * c) + col, a(row, 6 + col));
        }
      slot[r] = -1;
    }
  }
}

}  // namespace

std::vector<int> free_bodies(const MultibodySystem& sys) {
  const Model& m = sys.model();
  // Equilibrium, modes and frequency response all start here.
  if (!m.flexible.empty())
    throw InputError("flexible body '" + m.flexible.front().name +
                     "': the linearisation (equilibrium, modes, frf) does not take flexible bodies yet; mbsflow info PART.h5 "
                     "gives the reduced part's own frequencies");
  std::vector<char> driven(m.bodies.size(), 0);
  for (const Driver& d : m.drivers) driven[static_cast<std::size_t>(d.body)] = 1;
  std::vector<int> out;
  for (std::size_t b = 0; b < m.bodies.size(); ++b)
    if (!driven[b]) out.push_back(static_cast<int>(b));
  return out;
}

void apply_tangent_step(const StateLayout& l, const std::vector<int>& bodies, const Eigen::VectorXd& dx, Eigen::VectorXd& y) {
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const int b = bodies[k];
    const auto i = static_cast<Eigen::Index>(6 * k);
    y.segment<3>(l.position(b)) += dx.segment<3>(i);
    const Eigen::Vector3d phi = dx.segment<3>(i + 3);
    const auto q = y.segment<4>(l.orientation(b));
    Eigen::Quaterniond turned(q[0], q[1], q[2], q[3]);
    if (phi.norm() > 0.0) turned = Eigen::Quaterniond(Eigen::AngleAxisd(phi.norm(), phi.normalized())) * turned;
    turned.normalize();
    y.segment<4>(l.orientation(b)) << turned.w(), turned.x(), turned.y(), turned.z();
    y.segment<3>(l.velocity(b)).setZero();
    y.segment<3>(l.angular_velocity(b)).setZero();
  }
}

Eigen::VectorXd static_residual(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const std::vector<int>& bodies) {
  const StateLayout& l = sys.layout();
  Eigen::VectorXd at_rest = y;
  for (Eigen::Index b = 0; b < l.bodies; ++b) {
    at_rest.segment<3>(l.velocity(b)).setZero();
    at_rest.segment<3>(l.angular_velocity(b)).setZero();
  }
  Eigen::VectorXd dydt(l.size());
  sys.rhs(t, at_rest, dydt);
  Eigen::VectorXd f(6 * static_cast<Eigen::Index>(bodies.size()));
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const int b = bodies[k];
    const Body& body = sys.model().bodies[static_cast<std::size_t>(b)];
    const auto i = static_cast<Eigen::Index>(6 * k);
    f.segment<3>(i) = body.mass * dydt.segment<3>(l.velocity(b));
    f.segment<3>(i + 3) = rotation(y, l, b) * (body_inertia(body) * dydt.segment<3>(l.angular_velocity(b)));
  }
  return f;
}

LinearModel linearize(MultibodySystem& sys, double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>* jacobian) {
  const StateLayout& l = sys.layout();
  LinearModel out;
  out.model = &sys.model();
  out.t = t;
  out.state = y;
  out.bodies = free_bodies(sys);
  const auto n = static_cast<Eigen::Index>(out.bodies.size());
  if (n == 0) throw InputError("every body is driven: nothing moves freely to linearise");
  std::vector<Eigen::Matrix<double, 6, 6>> mass(out.bodies.size());
  Triplets masses, k, d;
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const int b = out.bodies[static_cast<std::size_t>(i)];
    mass[static_cast<std::size_t>(i)] = mass_block(sys.model().bodies[static_cast<std::size_t>(b)], rotation(y, l, b));
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c)
        if (const double v = mass[static_cast<std::size_t>(i)](r, c); v != 0.0 || r == c) masses.emplace_back(6 * i + r, 6 * i + c, v);
    fastest = std::max({fastest, y.segment<3>(l.velocity(b)).norm(), y.segment<3>(l.angular_velocity(b)).norm()});
  }
  out.M.resize(6 * n, 6 * n);
  out.M.setFromTriplets(masses.begin(), masses.end());
  out.K.resize(6 * n, 6 * n);
  out.D.resize(6 * n, 6 * n);
  if (sys.has_analytic_jacobian()) {
    Eigen::SparseMatrix<double> own;
    if (!jacobian) own = sys.jacobian_pattern();
    Eigen::SparseMatrix<double>& jac = jacobian ? *jacobian : own;
    sys.jacobian(t, y, jac);
    rate_blocks(l, out.bodies, y, jac, mass, k, d);
    out.K.setFromTriplets(k.begin(), k.end());
    out.D.setFromTriplets(d.begin(), d.end());
  } else {
    // Central differences in the tangent directions, then the rate rows of A = tp (J tm):
    // K = -M A_vx, D = -M A_vv.
    Eigen::SparseMatrix<double> tm, tp;
    tangent_maps(l, out.bodies, y, tm, tp);
    const Eigen::SparseMatrix<double> a = tp * differenced(sys, t, y, out.bodies);
    Triplets avx, avv;
    for (Eigen::Index c = 0; c < a.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) {
        if (it.row() < 6 * n) continue;
        (it.col() < 6 * n ? avx : avv).emplace_back(it.row() - 6 * n, it.col() < 6 * n ? it.col() : it.col() - 6 * n, it.value());
      }
    Eigen::SparseMatrix<double> dadx(6 * n, 6 * n), dadv(6 * n, 6 * n);
    dadx.setFromTriplets(avx.begin(), avx.end());
    dadv.setFromTriplets(avv.begin(), avv.end());
    out.K = -(out.M * dadx);
    out.D = -(out.M * dadv);
  }
  out.at_rest = fastest <= 1e-12;
  // The rigid joints' rows on the free bodies' coordinates (a driven body's are held).
  std::vector<int> joint_of_row;
  const Eigen::SparseMatrix<double> c = sys.constraint_jacobian(t, y, &joint_of_row);
  if (c.rows() > 0) {
    std::vector<Eigen::Index> column_of(static_cast<std::size_t>(6 * l.bodies), -1);
    for (Eigen::Index k = 0; k < n; ++k)
      for (int e = 0; e < 6; ++e) column_of[static_cast<std::size_t>(6 * out.bodies[static_cast<std::size_t>(k)] + e)] = 6 * k + e;
    Triplets rows;
    std::vector<char> used(static_cast<std::size_t>(c.rows()), 0);
    for (Eigen::Index col = 0; col < c.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(c, col); it; ++it)
        if (const Eigen::Index to = column_of[static_cast<std::size_t>(it.col())]; to >= 0) {
          rows.emplace_back(it.row(), to, it.value());
          used[static_cast<std::size_t>(it.row())] = 1;
        }
    // Rows on driven bodies or ground only hold nothing here.
    std::vector<Eigen::Index> row_to(used.size(), -1);
    Eigen::Index kept = 0;
    for (std::size_t r = 0; r < used.size(); ++r)
      if (used[r]) {
        row_to[r] = kept++;
        out.constraint_joint.push_back(joint_of_row[r]);
      }
    for (auto& e : rows) e = Eigen::Triplet<double>(row_to[static_cast<std::size_t>(e.row())], e.col(), e.value());
    out.C.resize(kept, 6 * n);
    out.C.setFromTriplets(rows.begin(), rows.end());
  } else {
    out.C.resize(0, 6 * n);
  }
  return out;
}

}  // namespace mbsflow
