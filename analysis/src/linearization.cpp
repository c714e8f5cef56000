#include "mbsflow/analysis/linearization.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mbsflow/error.hpp"
#include "parallel_over.hpp"

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

// T: tangent (x, v) of the free coordinates -> the state's numbers; T+: its left inverse.
void tangent_maps(const StateLayout& l, const FreeCoordinates& fc, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& t,
                  Eigen::SparseMatrix<double>& t_plus) {
  const Eigen::Index n = fc.size();
  Triplets a, b;
  for (std::size_t k = 0; k < fc.bodies.size(); ++k) {
    const int body = fc.bodies[k];
    const Eigen::Index x = fc.start[k], v = n + fc.start[k];
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
    if (const int f = fc.flexible_of(k); f >= 0) {
      const Eigen::Index ne = fc.modes(k), eta = fc.eta[static_cast<std::size_t>(f)];
      for (Eigen::Index i = 0; i < ne; ++i) {
        a.emplace_back(eta + i, x + 6 + i, 1.0);
        a.emplace_back(eta + ne + i, v + 6 + i, 1.0);
        b.emplace_back(x + 6 + i, eta + i, 1.0);
        b.emplace_back(v + 6 + i, eta + ne + i, 1.0);
      }
    }
  }
  t.resize(l.size(), 2 * n);
  t.setFromTriplets(a.begin(), a.end());
  t_plus.resize(2 * n, l.size());
  t_plus.setFromTriplets(b.begin(), b.end());
}

// The state moved by h along tangent direction `column` (0 .. 2 n).
Eigen::VectorXd moved(const StateLayout& l, const FreeCoordinates& fc, const Eigen::VectorXd& y, Eigen::Index column, double h) {
  const Eigen::Index n = fc.size();
  Eigen::VectorXd out = y;
  const bool rate = column >= n;
  const Eigen::Index local = rate ? column - n : column;
  const std::size_t k = fc.body_of(local);
  const int body = fc.bodies[k];
  const auto c = static_cast<int>(local - fc.start[k]);
  if (c >= 6) {  // a modal coordinate, or its rate
    const Eigen::Index ne = fc.modes(k);
    out[fc.eta[static_cast<std::size_t>(fc.flexible_of(k))] + (rate ? ne : 0) + c - 6] += h;
  } else if (!rate && c < 3) {
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
Eigen::SparseMatrix<double> differenced(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const FreeCoordinates& fc) {
  const StateLayout& l = sys.layout();
  const Eigen::Index columns = 2 * fc.size();
  Eigen::VectorXd plus(l.size()), minus(l.size());
  Triplets out;
  for (Eigen::Index c = 0; c < columns; ++c) {
    const double h = 1e-6;
    sys.rhs(t, moved(l, fc, y, c, h), plus);
    sys.rhs(t, moved(l, fc, y, c, -h), minus);
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

// A flexible body's mass matrix in the coordinates' rates (velocity and angular velocity
// in the world frame, modal rates): B^T M(eta) B, B = diag(R^T, R^T, I) their map to the
// frame's quasi-velocities.
Eigen::MatrixXd flexible_mass_block(const FloatingFrameData& d, const Eigen::VectorXd& eta, const Eigen::Matrix3d& R) {
  Eigen::MatrixXd m = flexible_mass_matrix(d, eta);
  for (Eigen::Index i : {0, 3}) {
    m.middleRows(i, 3) = (R * m.middleRows(i, 3)).eval();
    m.middleCols(i, 3) = (m.middleCols(i, 3) * R.transpose()).eval();
  }
  return m;
}

// The frame's accelerations as its quasi-velocities' rates (a body-frame, w' body-frame,
// eta'') from the state's rates at rest (no velocity terms).
Eigen::VectorXd at_rest_rates(const StateLayout& l, int frame, Eigen::Index eta, Eigen::Index ne, const Eigen::Matrix3d& R,
                              const Eigen::VectorXd& dydt) {
  Eigen::VectorXd xi(6 + ne);
  xi << R.transpose() * dydt.segment<3>(l.velocity(frame)), dydt.segment<3>(l.angular_velocity(frame)), dydt.segment(eta + ne, ne);
  return xi;
}

// K = -M A_vx and D = -M A_vv straight from the state Jacobian, body pair by body pair:
// A's rate rows of body r and tangent columns of body c are L_r J_rc T_c, where J_rc holds
// J's rows (orientation, velocity, angular velocity) of r and columns (all 13) of c, L_r is
// the tangent map's rate rows and T_c its columns. Equal to the products tp J tm of the
// general path without forming them (which took most of an equilibrium iteration on large
// models); every entry of a coupled pair is kept, so the pattern follows J's alone. K and
// D are written in place, column body by column body on all cores (a pair's 36 entries by
// one thread: the same numbers whatever the thread count); d == nullptr: K alone (the
// equilibrium needs no damping), which at rest reads J's position and orientation columns
// alone (the velocities' enter K through omega only).
void rate_blocks(const StateLayout& l, const FreeCoordinates& fc, const Eigen::VectorXd& y,
                 const Eigen::SparseMatrix<double>& jac, const std::vector<Eigen::Matrix<double, 6, 6>>& mass, bool at_rest,
                 Eigen::SparseMatrix<double>& k, Eigen::SparseMatrix<double>* d) {
  const Eigen::Index nb = l.bodies;
  const std::vector<int>& bodies = fc.bodies;
  const std::vector<int> index_of = fc.free_index(static_cast<std::size_t>(nb));
  using Left = Eigen::Matrix<double, 6, 10>;
  using Right = Eigen::Matrix<double, 13, 12>;
  std::vector<Left> left(bodies.size());
  std::vector<Right> right(bodies.size());
  parallel_over(bodies.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const int b = bodies[i];
      const Eigen::Vector4d q = y.segment<4>(l.orientation(b)).normalized();
      const Eigen::Matrix3d R = rotation(y, l, b);
      const Eigen::Vector3d omega = R * y.segment<3>(l.angular_velocity(b));
      const Eigen::Matrix<double, 4, 3> h = half_map(q);
      Left& L = left[i];  // rows: v (3), omega (3); columns: q (4), v (3), w (3) of the state
      L.setZero();
      L.block<3, 3>(0, 4).setIdentity();
      L.block<3, 4>(3, 0) = -skew(omega) * (2.0 * h.transpose());
      L.block<3, 3>(3, 7) = R;
      Right& T = right[i];  // rows: p, q, v, w of the state; columns: x (3 + 3), v (3 + 3)
      T.setZero();
      T.block<3, 3>(0, 0).setIdentity();
      T.block<4, 3>(3, 3) = 0.5 * h;
      T.block<3, 3>(7, 6).setIdentity();
      T.block<3, 3>(10, 3) = R.transpose() * skew(omega);
      T.block<3, 3>(10, 9) = R.transpose();
    }
  });
  // Where row s of the state lies: body, and row in J_rc (-1: a position row, not needed).
  const auto locate_row = [nb](Eigen::Index s, Eigen::Index& body) -> int {
    if (s < 3 * nb) return -1;
    if (s < 7 * nb) return body = (s - 3 * nb) / 4, static_cast<int>((s - 3 * nb) % 4);
    if (s < 10 * nb) return body = (s - 7 * nb) / 3, 4 + static_cast<int>((s - 7 * nb) % 3);
    return body = (s - 10 * nb) / 3, 7 + static_cast<int>((s - 10 * nb) % 3);
  };
  // The free bodies whose rates read column body c, in the order met, and with
  // with_blocks their J_rc (scratch reused from one column body to the next).
  struct Coupled {
    std::vector<int> rows;
    std::vector<Eigen::Matrix<double, 10, 13>> blocks;
  };
  const auto coupled = [&](std::size_t c, Coupled& out, bool with_blocks) {
    out.rows.clear();
    const int b = bodies[c];
    // jacobian_pattern gives each of a body's 13 columns the rates of every body that
    // reads it: the first column alone names them all, where only they are counted.
    const int count = !with_blocks ? 1 : d || !at_rest ? 13 : 7;
    const Eigen::Index columns[13] = {l.position(b),        l.position(b) + 1,    l.position(b) + 2,    l.orientation(b),
                                      l.orientation(b) + 1, l.orientation(b) + 2, l.orientation(b) + 3, l.velocity(b),
                                      l.velocity(b) + 1,    l.velocity(b) + 2,    l.angular_velocity(b),
                                      l.angular_velocity(b) + 1, l.angular_velocity(b) + 2};
    for (int j = 0; j < count; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(jac, columns[j]); it; ++it) {
        Eigen::Index body = 0;
        const int row = locate_row(it.row(), body);
        if (row < 0) continue;
        const int r = index_of[static_cast<std::size_t>(body)];
        if (r < 0) continue;  // a driven body's rows: no coordinates
        const auto slot = static_cast<std::size_t>(std::find(out.rows.begin(), out.rows.end(), r) - out.rows.begin());
        if (slot == out.rows.size()) {
          out.rows.push_back(r);
          if (with_blocks && out.blocks.size() < out.rows.size()) out.blocks.emplace_back();
          if (with_blocks) out.blocks[slot].setZero();
        }
        if (with_blocks) out.blocks[slot](row, j) = it.value();
      }
  };
  // Each column of body c holds 6 rows per coupled body: the columns' starts, then the values.
  const auto n = 6 * static_cast<Eigen::Index>(bodies.size());
  std::vector<int> pairs(bodies.size() + 1, 0);
  parallel_over(bodies.size(), [&](std::size_t begin, std::size_t end) {
    Coupled scratch;
    for (std::size_t c = begin; c != end; ++c) {
      coupled(c, scratch, false);
      pairs[c + 1] = static_cast<int>(scratch.rows.size());
    }
  });
  for (std::size_t c = 0; c < bodies.size(); ++c) pairs[c + 1] += pairs[c];
  for (Eigen::SparseMatrix<double>* m : {&k, d}) {
    if (!m) continue;
    m->resize(n, n);
    m->resizeNonZeros(36 * static_cast<Eigen::Index>(pairs.back()));
    int* outer = m->outerIndexPtr();
    for (std::size_t c = 0; c < bodies.size(); ++c)
      for (int col = 0; col < 6; ++col) outer[6 * c + static_cast<std::size_t>(col)] = 36 * pairs[c] + 6 * col * (pairs[c + 1] - pairs[c]);
    outer[n] = 36 * pairs.back();
  }
  parallel_over(bodies.size(), [&](std::size_t begin, std::size_t end) {
    Coupled scratch;
    for (std::size_t c = begin; c != end; ++c) {
      coupled(c, scratch, true);
      if (static_cast<int>(scratch.rows.size()) != pairs[c + 1] - pairs[c])
        throw std::logic_error("linearize: a Jacobian not of jacobian_pattern()'s pattern");
      for (std::size_t i = 0; i < scratch.rows.size(); ++i) {
        const auto r = static_cast<std::size_t>(scratch.rows[i]);
        // Its place in the columns: the rows ascend, so after every coupled body below it.
        const auto place = std::count_if(scratch.rows.begin(), scratch.rows.end(), [&](int other) { return other < scratch.rows[i]; });
        // Coefficient by coefficient: Eigen's blocked product (packing, kernels) at these
        // sizes took half of this loop.
        const Eigen::Matrix<double, 6, 13> lj = left[r].lazyProduct(scratch.blocks[i]);
        Eigen::Matrix<double, 6, 12> a;
        a.leftCols<6>() = -mass[r].lazyProduct(Eigen::Matrix<double, 6, 6>(lj.lazyProduct(right[c].leftCols<6>())));
        if (d) a.rightCols<6>() = -mass[r].lazyProduct(Eigen::Matrix<double, 6, 6>(lj.lazyProduct(right[c].rightCols<6>())));
        for (int col = 0; col < 6; ++col) {
          const Eigen::Index at = k.outerIndexPtr()[6 * c + static_cast<std::size_t>(col)] + 6 * place;
          for (int row = 0; row < 6; ++row) {
            k.innerIndexPtr()[at + row] = static_cast<int>(6 * r) + row;
            k.valuePtr()[at + row] = a(row, col);
            if (d) {
              d->innerIndexPtr()[at + row] = static_cast<int>(6 * r) + row;
              d->valuePtr()[at + row] = a(row, 6 + col);
            }
          }
        }
      }
    }
  });
}

}  // namespace

std::size_t FreeCoordinates::body_of(Eigen::Index i) const {
  return static_cast<std::size_t>(std::upper_bound(start.begin(), start.end() - 1, i) - start.begin() - 1);
}

std::vector<int> FreeCoordinates::free_index(std::size_t system_bodies) const {
  std::vector<int> out(system_bodies, -1);
  for (std::size_t k = 0; k < bodies.size(); ++k) out[static_cast<std::size_t>(bodies[k])] = static_cast<int>(k);
  return out;
}

FreeCoordinates free_coordinates(const MultibodySystem& sys) {
  const Model& m = sys.model();
  FreeCoordinates out;
  std::vector<char> held(m.bodies.size(), 0);  // driven, or a flexible body's node
  for (const Driver& d : m.drivers) held[static_cast<std::size_t>(d.body)] = 1;
  std::vector<int> frame_of(m.flexible.empty() ? 0 : m.bodies.size(), -1);
  for (std::size_t f = 0; f < m.flexible.size(); ++f) {
    for (int b : m.flexible[f].nodes) held[static_cast<std::size_t>(b)] = 1;
    frame_of[static_cast<std::size_t>(m.flexible[f].frame)] = static_cast<int>(f);
    out.eta.push_back(sys.flexible_state(f));
  }
  out.start.reserve(m.bodies.size() + 1);
  Eigen::Index next = 0;
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    if (held[b]) continue;
    out.bodies.push_back(static_cast<int>(b));
    out.start.push_back(next);
    next += 6;
    if (!frame_of.empty()) {
      out.flexible.push_back(frame_of[b]);
      if (frame_of[b] >= 0) next += m.flexible[static_cast<std::size_t>(frame_of[b])].data->modes();
    }
  }
  out.start.push_back(next);
  return out;
}

void set_at_rest(const StateLayout& l, const FreeCoordinates& c, Eigen::VectorXd& y) {
  for (Eigen::Index b = 0; b < l.bodies; ++b) {
    y.segment<3>(l.velocity(b)).setZero();
    y.segment<3>(l.angular_velocity(b)).setZero();
  }
  // The modal rates follow the modal coordinates: the tail's second half of each body.
  for (std::size_t k = 0; k < c.bodies.size(); ++k)
    if (const int f = c.flexible_of(k); f >= 0) y.segment(c.eta[static_cast<std::size_t>(f)] + c.modes(k), c.modes(k)).setZero();
}

void apply_tangent_step(const StateLayout& l, const FreeCoordinates& c, const Eigen::VectorXd& dx, Eigen::VectorXd& y) {
  for (std::size_t k = 0; k < c.bodies.size(); ++k) {
    const int b = c.bodies[k];
    const Eigen::Index i = c.start[k];
    y.segment<3>(l.position(b)) += dx.segment<3>(i);
    const Eigen::Vector3d phi = dx.segment<3>(i + 3);
    const auto q = y.segment<4>(l.orientation(b));
    Eigen::Quaterniond turned(q[0], q[1], q[2], q[3]);
    if (phi.norm() > 0.0) turned = Eigen::Quaterniond(Eigen::AngleAxisd(phi.norm(), phi.normalized())) * turned;
    turned.normalize();
    y.segment<4>(l.orientation(b)) << turned.w(), turned.x(), turned.y(), turned.z();
    if (const int f = c.flexible_of(k); f >= 0) y.segment(c.eta[static_cast<std::size_t>(f)], c.modes(k)) += dx.segment(i + 6, c.modes(k));
  }
  set_at_rest(l, c, y);
}

Eigen::VectorXd static_residual(MultibodySystem& sys, double t, const Eigen::VectorXd& y, const FreeCoordinates& c) {
  const StateLayout& l = sys.layout();
  Eigen::VectorXd at_rest = y;
  set_at_rest(l, c, at_rest);
  Eigen::VectorXd dydt(l.size());
  sys.rhs(t, at_rest, dydt);
  const Model& m = sys.model();
  Eigen::VectorXd f(c.size());
  for (std::size_t k = 0; k < c.bodies.size(); ++k) {
    const int b = c.bodies[k];
    const Eigen::Index i = c.start[k];
    const Eigen::Matrix3d R = rotation(y, l, b);
    if (const int fb = c.flexible_of(k); fb >= 0) {
      // B^T M xi' with B^T = diag(R, R, I): the frame's force and torque in the world frame.
      const FloatingFrameData& d = *m.flexible[static_cast<std::size_t>(fb)].data;
      const Eigen::Index eta = c.eta[static_cast<std::size_t>(fb)], ne = d.modes();
      Eigen::VectorXd g = flexible_mass_matrix(d, y.segment(eta, ne)) * at_rest_rates(l, b, eta, ne, R, dydt);
      f.segment<3>(i) = R * g.head<3>();
      f.segment<3>(i + 3) = R * g.segment<3>(3);
      f.segment(i + 6, ne) = g.tail(ne);
      continue;
    }
    const Body& body = m.bodies[static_cast<std::size_t>(b)];
    f.segment<3>(i) = body.mass * dydt.segment<3>(l.velocity(b));
    f.segment<3>(i + 3) = R * (body_inertia(body) * dydt.segment<3>(l.angular_velocity(b)));
  }
  return f;
}

Eigen::SparseMatrix<double> body_motion(const LinearModel& lm) {
  const Model& m = *lm.model;
  const FreeCoordinates& c = lm.coords;
  const StateLayout l{static_cast<Eigen::Index>(m.bodies.size()), lm.state.size() - 13 * static_cast<Eigen::Index>(m.bodies.size())};
  Triplets e;
  e.reserve(6 * c.bodies.size());
  for (std::size_t k = 0; k < c.bodies.size(); ++k)
    for (int i = 0; i < 6; ++i) e.emplace_back(6 * c.bodies[k] + i, c.start[k] + i, 1.0);
  // A node of a flexible body: its frame's motion carried to where it is (translation
  // dx + dphi x R r), and the modes' displacement and rotation there, turned with the frame.
  for (std::size_t k = 0; k < c.bodies.size(); ++k) {
    const int f = c.flexible_of(k);
    if (f < 0) continue;
    const FlexibleBody& fb = m.flexible[static_cast<std::size_t>(f)];
    const FloatingFrameData& d = *fb.data;
    const Eigen::Index ne = d.modes(), x = c.start[k];
    const Eigen::VectorXd eta = lm.state.segment(c.eta[static_cast<std::size_t>(f)], ne);
    const Eigen::Matrix3d R = rotation(lm.state, l, fb.frame);
    for (std::size_t n = 0; n < fb.nodes.size(); ++n) {
      const Eigen::Index row = 6 * fb.nodes[n];
      const Eigen::MatrixXd& shape = d.node_shape[n];
      const Eigen::Matrix3d arm = -skew(R * (d.node_position[n] + shape.topRows<3>() * eta));
      const Eigen::MatrixXd turned = R * shape.topRows<3>(), turned_rotation = R * shape.bottomRows<3>();
      for (int i = 0; i < 3; ++i) {
        e.emplace_back(row + i, x + i, 1.0);
        e.emplace_back(row + 3 + i, x + 3 + i, 1.0);
        for (int j = 0; j < 3; ++j) e.emplace_back(row + i, x + 3 + j, arm(i, j));
        for (Eigen::Index j = 0; j < ne; ++j) {
          e.emplace_back(row + i, x + 6 + j, turned(i, j));
          e.emplace_back(row + 3 + i, x + 6 + j, turned_rotation(i, j));
        }
      }
    }
  }
  Eigen::SparseMatrix<double> w(6 * static_cast<Eigen::Index>(m.bodies.size()), c.size());
  w.setFromTriplets(e.begin(), e.end());
  return w;
}

LinearModel linearize(MultibodySystem& sys, double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>* jacobian,
                      bool with_damping) {
  LinearModel out;
  linearize_into(out, sys, t, y, jacobian, with_damping);
  return out;
}

void linearize_into(LinearModel& out, MultibodySystem& sys, double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>* jacobian,
                    bool with_damping) {
  const StateLayout& l = sys.layout();
  const Model& model = sys.model();
  out.constraint_joint.clear();
  out.constraint_row.clear();
  out.model = &model;
  out.t = t;
  out.state = y;
  out.coords = free_coordinates(sys);
  const FreeCoordinates& fc = out.coords;
  const std::vector<int>& bodies = fc.bodies;
  const Eigen::Index n = fc.size();
  if (bodies.empty()) throw InputError("every body is driven: nothing moves freely to linearise");
  std::vector<Eigen::Matrix<double, 6, 6>> mass(bodies.size());
  Triplets masses;
  double fastest = 0.0;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const int b = bodies[i];
    const Eigen::Index at = fc.start[i];
    fastest = std::max({fastest, y.segment<3>(l.velocity(b)).norm(), y.segment<3>(l.angular_velocity(b)).norm()});
    if (const int f = fc.flexible_of(i); f >= 0) {
      const FloatingFrameData& data = *model.flexible[static_cast<std::size_t>(f)].data;
      const Eigen::Index eta = fc.eta[static_cast<std::size_t>(f)];
      const Eigen::MatrixXd block = flexible_mass_block(data, y.segment(eta, data.modes()), rotation(y, l, b));
      for (Eigen::Index r = 0; r < block.rows(); ++r)
        for (Eigen::Index c = 0; c < block.cols(); ++c)
          if (block(r, c) != 0.0 || r == c) masses.emplace_back(at + r, at + c, block(r, c));
      fastest = std::max(fastest, y.segment(eta + data.modes(), data.modes()).cwiseAbs().maxCoeff());
      continue;
    }
    mass[i] = mass_block(model.bodies[static_cast<std::size_t>(b)], rotation(y, l, b));
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c)
        if (const double v = mass[i](r, c); v != 0.0 || r == c) masses.emplace_back(at + r, at + c, v);
  }
  out.M.resize(n, n);
  out.M.setFromTriplets(masses.begin(), masses.end());
  out.K.resize(n, n);
  out.D.resize(n, n);
  const bool at_rest = fastest <= 1e-12;
  const bool analytic = sys.has_analytic_jacobian();
  Eigen::SparseMatrix<double> own;
  Eigen::SparseMatrix<double>& jac = jacobian ? *jacobian : own;
  if (analytic) {
    if (jac.size() == 0) {
      Eigen::SparseMatrix<double> pattern = sys.jacobian_pattern();
      jac.swap(pattern);  // Eigen 3.4's SparseMatrix has no move: an assignment copies
    }
    sys.jacobian(t, y, jac, all_cores(), with_damping || !at_rest);
  }
  if (analytic && model.flexible.empty()) {  // rate_blocks: 6 coordinates per body
    rate_blocks(l, fc, y, jac, mass, at_rest, out.K, with_damping ? &out.D : nullptr);
  } else {
    // The rate rows of A = T+ (J T), J T exact or by central differences in the tangent
    // directions: K = -M A_vx, D = -M A_vv.
    Eigen::SparseMatrix<double> tm, tp;
    tangent_maps(l, fc, y, tm, tp);
    const Eigen::SparseMatrix<double> a = tp * (analytic ? Eigen::SparseMatrix<double>(jac * tm) : differenced(sys, t, y, fc));
    Triplets avx, avv;
    for (Eigen::Index c = 0; c < a.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) {
        if (it.row() < n) continue;
        (it.col() < n ? avx : avv).emplace_back(it.row() - n, it.col() < n ? it.col() : it.col() - n, it.value());
      }
    Eigen::SparseMatrix<double> dadx(n, n), dadv(n, n);
    dadx.setFromTriplets(avx.begin(), avx.end());
    dadv.setFromTriplets(avv.begin(), avv.end());
    out.K = -(out.M * dadx);
    if (with_damping) out.D = -(out.M * dadv);
  }
  out.at_rest = at_rest;
  // The rigid joints' rows on the free bodies' coordinates (a driven body's are held).
  std::vector<int> joint_of_row;
  const Eigen::SparseMatrix<double> c = sys.constraint_jacobian(t, y, &joint_of_row);
  if (c.rows() > 0) {
    Triplets rows;
    std::vector<char> used(static_cast<std::size_t>(c.rows()), 0);
    auto keep = [&](Eigen::Index row, Eigen::Index col, double value) {
      rows.emplace_back(row, col, value);
      used[static_cast<std::size_t>(row)] = 1;
    };
    if (!model.flexible.empty()) {
      // A row at a flexible body's node reads its frame's motion and the modes there.
      const Eigen::SparseMatrix<double> on_coordinates = c * body_motion(out);
      for (Eigen::Index col = 0; col < on_coordinates.outerSize(); ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(on_coordinates, col); it; ++it)
          if (it.value() != 0.0) keep(it.row(), it.col(), it.value());
    } else {
      std::vector<Eigen::Index> column_of(static_cast<std::size_t>(6 * l.bodies), -1);
      for (std::size_t i = 0; i < bodies.size(); ++i)
        for (int e = 0; e < 6; ++e) column_of[static_cast<std::size_t>(6 * bodies[i] + e)] = fc.start[i] + e;
      for (Eigen::Index col = 0; col < c.outerSize(); ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(c, col); it; ++it)
          if (const Eigen::Index to = column_of[static_cast<std::size_t>(it.col())]; to >= 0) keep(it.row(), to, it.value());
    }
    // Rows on driven bodies or ground only hold nothing here.
    std::vector<Eigen::Index> row_to(used.size(), -1);
    Eigen::Index kept = 0;
    for (std::size_t r = 0; r < used.size(); ++r)
      if (used[r]) {
        row_to[r] = kept++;
        out.constraint_joint.push_back(joint_of_row[r]);
        out.constraint_row.push_back(static_cast<Eigen::Index>(r));
      }
    for (auto& e : rows) e = Eigen::Triplet<double>(row_to[static_cast<std::size_t>(e.row())], e.col(), e.value());
    out.C.resize(kept, n);
    out.C.setFromTriplets(rows.begin(), rows.end());
  } else {
    out.C.resize(0, n);
  }
}

}  // namespace mbsflow
