// Rigid joints at flexible bodies (docs/flexible.md). A cluster that holds a flexible
// body's frame or nodes is solved in generalised velocities u: each rigid body's (v, w),
// world axes, and each flexible body's xi = [v_b, w, eta'] (flexible_body.hpp) once for
// its frame and all its nodes. A slot of a flexible body moves by
//   (v, w) = T xi,  (a, alpha) = T xi' + gamma  (flexible_cluster.hpp).
// The rows become G = J T, their bias grows by J gamma, and the multipliers solve
//   G M^-1 G^T lambda = -(G u'_free + bias),  M = blockdiag(m I, I_world, M(eta) ...),
// shifted and refined where the rows are redundant as RigidCluster does. The projection
// after a step moves the frame (body axes), its turn and the modal coordinates the same
// way, mass-weighted by M(eta). Clusters are small here (a part's few joints): dense.
#include <Eigen/Cholesky>
#include <algorithm>

#include "constraint_rows.hpp"
#include "flexible_cluster.hpp"
#include "flexible_state.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "multibody_constraints.hpp"
#include "rigid_cluster.hpp"
#include "rotation.hpp"

namespace mbsflow {
namespace {

using flexible_cluster::solve_rows;
using SlotMap = flexible_cluster::SlotMapT<double>;

// Slot `node` (-1: the frame) of the flexible body at f, its frame turned by r, moving
// with v_b (frame axes).
SlotMap slot_map(const FlexibleAt& f, const Eigen::Matrix3d& r, const Eigen::Vector3d& v_b, int node) {
  return flexible_cluster::slot_map<double>(f.d, r, v_b, f.w, f.eta, f.eta_rate, node);
}

// One evaluation of a cluster in generalised velocities.
struct Generalised {
  std::vector<SlotMap> map;                         // per slot of a flexible body
  std::vector<Eigen::LDLT<Eigen::MatrixXd>> mass;   // per flexible body: M(eta)
  Eigen::MatrixXd g;                                // rows x size: J T
  Eigen::VectorXd bias;                             // rows: the rows' bias + J gamma
  Eigen::MatrixXd w_gt;                             // size x rows: M^-1 G^T
  Eigen::MatrixXd s;                                // G M^-1 G^T
};

// G, bias, M^-1 G^T and S from the cluster's evaluated rows, its rigid slots' inverse
// masses (rc.inv_mass, rc.inv_inertia) and gen's maps and factored masses.
void assemble(Generalised& gen, const RigidCluster& rc, const FlexibleSlots& fs) {
  const int rows = rc.row_count();
  gen.g.setZero(rows, fs.size);
  gen.bias.resize(rows);
  for (const ClusterJoint& cj : rc.joints())
    for (int r = cj.first_row; r < cj.first_row + cj.rows; ++r) {
      const ConstraintRow& row = rc.rows[static_cast<std::size_t>(r)];
      gen.bias[r] = row.bias;
      for (int side = 0; side < 2; ++side) {
        const int s = side == 0 ? cj.a : cj.b;
        if (s < 0) continue;  // ground
        const Vector6d j = row.j.segment<6>(6 * side);
        const auto slot = static_cast<std::size_t>(s);
        if (fs.owner[slot] < 0) {
          gen.g.row(r).segment<6>(fs.start[slot]) += j.transpose();
        } else {
          const SlotMap& m = gen.map[slot];
          gen.g.row(r).segment(fs.start[slot], m.t.cols()) += j.transpose() * m.t;
          gen.bias[r] += j.dot(m.gamma);
        }
      }
    }
  gen.w_gt.resize(fs.size, rows);
  const Eigen::MatrixXd gt = gen.g.transpose();
  for (std::size_t s = 0; s < fs.owner.size(); ++s) {
    if (fs.owner[s] >= 0) continue;
    const Eigen::Index at = fs.start[s];
    gen.w_gt.middleRows<3>(at) = rc.inv_mass[s] * gt.middleRows<3>(at);
    gen.w_gt.middleRows<3>(at + 3) = rc.inv_inertia[s] * gt.middleRows<3>(at + 3);
  }
  for (std::size_t f = 0; f < fs.block.size(); ++f) {
    const Eigen::LDLT<Eigen::MatrixXd>& m = gen.mass[f];
    gen.w_gt.middleRows(fs.block[f], m.rows()) = m.solve(gt.middleRows(fs.block[f], m.rows()));
  }
  gen.s.noalias() = gen.g * gen.w_gt;
}

// The cluster's flexible bodies at y (FlexibleAt each), their masses M(eta) factored and
// their slots' maps into gen; frame_rotation(body): the frame's rotation matrix.
template <class Rotation>
std::vector<FlexibleAt> flexible_members(const Model& m, const StateLayout& l, const std::vector<Eigen::Index>& tails,
                                         const FlexibleSlots& fs, const Eigen::VectorXd& y, Rotation frame_rotation, Generalised& gen) {
  std::vector<FlexibleAt> at;
  std::vector<Eigen::Matrix3d> r;
  std::vector<Eigen::Vector3d> v_b;
  gen.map.resize(fs.owner.size());
  gen.mass.resize(fs.flexible.size());
  for (std::size_t i = 0; i < fs.flexible.size(); ++i) {
    const auto f = static_cast<std::size_t>(fs.flexible[i]);
    at.push_back(flexible_at(m.flexible[f], l, tails[f], y));
    r.push_back(frame_rotation(at[i].frame));
    v_b.push_back(r[i].transpose() * y.segment<3>(l.velocity(at[i].frame)));
    gen.mass[i].compute(flexible_mass_matrix(at[i].d, at[i].eta));
  }
  for (std::size_t s = 0; s < fs.owner.size(); ++s)
    if (const int i = fs.owner[s]; i >= 0) {
      const auto k = static_cast<std::size_t>(i);
      gen.map[s] = slot_map(at[k], r[k], v_b[k], fs.node[s]);
    }
  return at;
}

}  // namespace

void MultibodySystem::join_flexible_pieces(std::vector<char>& touched, std::vector<int>& piece) const {
  for (const FlexibleBody& fb : model().flexible) {
    std::vector<int> held;
    for (int b : fb.nodes)
      if (touched[static_cast<std::size_t>(b)]) held.push_back(b);
    if (held.empty() && !touched[static_cast<std::size_t>(fb.frame)]) continue;
    touched[static_cast<std::size_t>(fb.frame)] = 1;
    const int into = piece[static_cast<std::size_t>(fb.frame)];
    for (int b : held)
      if (const int from = piece[static_cast<std::size_t>(b)]; from != into) std::replace(piece.begin(), piece.end(), from, into);
  }
}

FlexibleSlots MultibodySystem::flexible_slots(const std::vector<int>& bodies) const {
  FlexibleSlots fs;
  if (compiled_->flexible_of_body.empty()) return fs;
  fs.owner.assign(bodies.size(), -1);
  fs.node.assign(bodies.size(), -1);
  fs.start.assign(bodies.size(), 0);
  for (std::size_t s = 0; s < bodies.size(); ++s) {
    const int f = compiled_->flexible_of_body[static_cast<std::size_t>(bodies[s])];
    if (f < 0) {
      fs.start[s] = fs.size;
      fs.size += 6;
      continue;
    }
    auto it = std::find(fs.flexible.begin(), fs.flexible.end(), f);
    if (it == fs.flexible.end()) {
      fs.flexible.push_back(f);
      fs.block.push_back(fs.size);
      fs.size += 6 + model().flexible[static_cast<std::size_t>(f)].data->modes();
      it = fs.flexible.end() - 1;
    }
    const auto owner = static_cast<std::size_t>(it - fs.flexible.begin());
    fs.owner[s] = static_cast<int>(owner);
    fs.start[s] = fs.block[owner];
    const std::vector<int>& nodes = model().flexible[static_cast<std::size_t>(f)].nodes;
    const auto node = std::find(nodes.begin(), nodes.end(), bodies[s]);
    fs.node[s] = node == nodes.end() ? -1 : static_cast<int>(node - nodes.begin());
  }
  if (fs.flexible.empty()) return {};
  return fs;
}

void MultibodySystem::solve_flexible_cluster(int c, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  Constraints& k = *constraints_;
  RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const FlexibleSlots& fs = *k.flexible_slots_of(c);
  const std::vector<int>& bodies = rc.bodies();
  unconstrained_cluster(c, t, y);  // the rigid slots
  Eigen::VectorXd accel(fs.size);  // u' under the applied forces alone
  for (std::size_t s = 0; s < bodies.size(); ++s)
    if (fs.owner[s] < 0) accel.segment<6>(fs.start[s]) = k.wrench[s];
  Generalised gen;
  const std::vector<FlexibleAt> at = flexible_members(model(), layout_, compiled_->flexible_tail, fs, y,
                                                      [&](int frame) { return rot_[static_cast<std::size_t>(frame)]; }, gen);
  const std::vector<Eigen::Index>& block = fs.block;
  for (std::size_t i = 0; i < fs.flexible.size(); ++i) {
    const auto f = static_cast<std::size_t>(fs.flexible[i]);
    accel.segment(block[i], 6 + at[i].ne) = free_flexible_accelerations(f, at[i], y, flexible_force(f, at[i], t, y));
  }
  for (const ClusterJoint& cj : rc.joints()) {
    const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
    evaluate_constraint(geometry_of(j), motion_at(j.a), motion_at(j.b), t, rc.rows.data() + cj.first_row);
  }
  assemble(gen, rc, fs);
  Eigen::VectorXd& lambda = k.lambda[static_cast<std::size_t>(c)];
  lambda = -(gen.g * accel + gen.bias);
  solve_rows(gen.s, lambda);
  accel.noalias() += gen.w_gt * lambda;
  rc.wrenches(lambda, k.wrench);
  for (std::size_t s = 0; s < bodies.size(); ++s)
    if (fs.owner[s] < 0)
      write_derivative(bodies[s], t, y, dydt, k.force[s] + k.wrench[s].head<3>(), k.torque[s] + k.wrench[s].tail<3>());
  for (std::size_t i = 0; i < fs.flexible.size(); ++i)
    write_flexible_rates(static_cast<std::size_t>(fs.flexible[i]), at[i], accel.segment(block[i], 6 + at[i].ne), y, dydt);
}

void MultibodySystem::project_flexible_cluster(int c, double t, Eigen::VectorXd& y) const {
  Constraints& k = *constraints_;
  RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const FlexibleSlots& fs = *k.flexible_slots_of(c);
  const std::vector<int>& bodies = rc.bodies();
  Generalised gen;
  // Nodes placed, rows, inverse masses, maps and S at y; the largest position violation.
  auto evaluate = [&] {
    for (int f : fs.flexible) place_nodes_of(static_cast<std::size_t>(f), y);
    double worst = 0.0;
    for (const ClusterJoint& cj : rc.joints()) {
      const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
      ConstraintRow* rows = rc.rows.data() + cj.first_row;
      evaluate_constraint(geometry_of(j), state_motion(layout_, y, j.a), state_motion(layout_, y, j.b), t, rows);
      for (int r = 0; r < cj.rows; ++r)
        if (rows[r].holonomic) worst = std::max(worst, std::abs(rows[r].phi));
    }
    auto rotation = [&](Eigen::Index i) { return rotation_matrix(Eigen::Vector4d(y.segment<4>(layout_.orientation(i)))); };
    flexible_members(model(), layout_, compiled_->flexible_tail, fs, y, rotation, gen);
    for (std::size_t s = 0; s < bodies.size(); ++s) {
      const auto i = static_cast<std::size_t>(bodies[s]);
      if (fs.owner[s] >= 0) continue;
      const bool driven = compiled_->driver_of_body[i] >= 0;
      const Eigen::Matrix3d r = rotation(bodies[s]);
      rc.inv_mass[s] = driven ? 0.0 : body_law(i).inv_mass;
      rc.inv_inertia[s] = driven ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(r * body_law(i).inv_inertia * r.transpose());
    }
    assemble(gen, rc, fs);
    return worst;
  };
  // Move by du = M^-1 G^T mu: positions and turns, or velocities.
  auto move = [&](const Eigen::VectorXd& du, bool positions) {
    for (std::size_t s = 0; s < bodies.size(); ++s) {
      const bool flexible = fs.owner[s] >= 0;
      if (flexible && fs.node[s] >= 0) continue;  // a node follows its frame
      const Eigen::Index i = bodies[s], at = fs.start[s];
      const Eigen::Matrix3d r = rotation_matrix(Eigen::Vector4d(y.segment<4>(layout_.orientation(i))));
      // A rigid body's translation and turn are in world axes, a frame's in its own.
      const Eigen::Vector3d dx = flexible ? Eigen::Vector3d(r * du.segment<3>(at)) : Eigen::Vector3d(du.segment<3>(at));
      const Eigen::Vector3d dtheta = flexible ? Eigen::Vector3d(r * du.segment<3>(at + 3)) : Eigen::Vector3d(du.segment<3>(at + 3));
      if (positions) {
        y.segment<3>(layout_.position(i)) += dx;
        y.segment<4>(layout_.orientation(i)) = quat_multiply(quat_exp(dtheta), y.segment<4>(layout_.orientation(i))).normalized();
      } else {
        y.segment<3>(layout_.velocity(i)) += dx;
        y.segment<3>(layout_.angular_velocity(i)) += r.transpose() * dtheta;
      }
      if (!flexible) continue;
      const auto f = static_cast<std::size_t>(fs.flexible[static_cast<std::size_t>(fs.owner[s])]);
      const int ne = model().flexible[f].data->modes();
      y.segment(layout_.tail(compiled_->flexible_tail[f]) + (positions ? 0 : ne), ne) += du.segment(at + 6, ne);
    }
  };
  Eigen::VectorXd mu(rc.row_count());
  bool current = false;
  for (int iteration = 0; iteration < projection_iterations; ++iteration) {
    current = true;
    if (evaluate() <= projection_tolerance) break;
    for (int r = 0; r < rc.row_count(); ++r) {
      const ConstraintRow& row = rc.rows[static_cast<std::size_t>(r)];
      mu[r] = row.holonomic ? -row.phi : 0.0;
    }
    solve_rows(gen.s, mu);
    move(gen.w_gt * mu, true);
    current = false;
  }
  if (!current) evaluate();
  // Velocities: remove the part that violates phi' = 0.
  velocity_violations(rc, y, mu);
  solve_rows(gen.s, mu);
  move(gen.w_gt * mu, false);
  for (int f : fs.flexible) place_nodes_of(static_cast<std::size_t>(f), y);
}

}  // namespace mbsflow
