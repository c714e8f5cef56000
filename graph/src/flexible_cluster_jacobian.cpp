// The analytic Jacobian of a rigid cluster that holds flexible bodies (or whose bodies
// read a flexible body's modes). Its rates solve, in generalised velocities u
// (flexible_joints.cpp; a rigid body's (v, w) in world axes, a flexible body's
// [v_b, w, eta']),
//   M u' = f + G^T lambda,  G u' + b = 0,
// M = blockdiag(m I, I_world, M(eta) ...), f the applied and inertial forces (a rigid
// body's (F, T - R (w x J w)), a flexible body's right side, flexible_dynamics::balance),
// G = J T and b = bias + J gamma (flexible_cluster.hpp). At the solution (u'0, lambda0)
// the right-hand side just found, along the state,
//   M du' - G^T dlambda = d(f + G^T lambda0 - M u'0) =: r1,   G du' = -d(G u'0 + b) =: r2,
// so S dlambda = r2 - G W r1 and du' = W (r1 + G^T dlambda), W = M^-1 (zero for a driven
// body). r1 and r2 are differentiated in dual numbers over every state number the
// cluster's rates read (the arithmetic the right-hand side runs), and W, G and S are
// their values: one factor of S for all the columns.
#include <array>
#include <unsupported/Eigen/AutoDiff>

#include "flexible_cluster.hpp"
#include "flexible_dynamics.hpp"
#include "flexible_state.hpp"
#include "jacobian_seeds.hpp"
#include "multibody_constraints.hpp"

namespace mbsflow {
namespace {

using flexible_dynamics::MatrixT;
using flexible_dynamics::VectorT;
using jacobian_seeds::body_states;
using jacobian_seeds::BodyNumbers;
using jacobian_seeds::HeapDual;
using jacobian_seeds::stack_variables;
using jacobian_seeds::StackDual;

// An applied wrench (world force, torque) and its derivatives by the variables.
struct AppliedWrench {
  Vector6d value = Vector6d::Zero();
  Eigen::MatrixXd derivatives;  // 6 x variables
};

// A cluster's slot as the Jacobian reads it.
struct Slot {
  int flexible = -1, node = -1;  // its flexible member and node (-1: the frame), or -1: a rigid body
  int first = -1;                // a free rigid body's first variable; -1: driven (a fixed motion)
  BodyNumbers numbers;           // a rigid body's state numbers
  BodyMotion fixed;              // a driven body's motion
  double mass = 0.0, inv_mass = 0.0;  // inv_mass 0 for a driven body
  Eigen::Matrix3d inertia;           // body axes
  Eigen::Matrix3d inv_inertia;       // world axes, as the right-hand side's solve took it (0: driven)
  AppliedWrench wrench;  // a free rigid body's applied wrench
};

// A flexible body of the cluster.
struct Member {
  const FlexibleBody* body = nullptr;
  int first = 0;  // its frame's first variable; then eta, then eta'
  BodyNumbers frame;
  Eigen::VectorXd eta, eta_rate;
  std::vector<AppliedWrench> wrench;  // its frame's (gravity on the part in it), then each node's
};

struct ClusterInputs {
  int variables = 0;
  double t = 0.0;
  Eigen::Vector3d gravity;
  std::vector<Slot> slots;
  std::vector<Member> members;
  std::vector<Eigen::Index> start;  // per slot: its first generalised velocity (a flexible body's block)
  std::vector<Eigen::Index> block;  // per member: its block's first generalised velocity
  Eigen::Index size = 0;
  struct Joint {
    const JointGeometry* geometry;
    int a, b;             // slots, -1: ground
    BodyMotion ground_a, ground_b;
    int first_row, rows;
  };
  std::vector<Joint> joints;
  int rows = 0;
  Eigen::VectorXd u_rate, lambda;  // u'0 and lambda0
};

template <class D>
D dual(double value, const Eigen::MatrixXd& derivatives, int row) {
  return D(value, derivatives.row(row).transpose());
}

template <class D>
Eigen::MatrixXd derivatives_of(const VectorT<D>& x, int variables) {
  Eigen::MatrixXd out(x.size(), variables);
  jacobian_seeds::put_rows(x, 0, variables, out);
  return out;
}

// A flexible member in dual numbers: its frame's numbers and modes seeded, its rotation
// and its velocity in its own axes.
template <class D>
struct FlexibleEval {
  jacobian_seeds::SeededModes<D> frame;
  Matrix3T<D> r;
  Vector3T<D> v_b;
};

// The derivatives of the cluster's rates by the variables: per free rigid slot v' (world)
// and w' (body), per member its frame's v' (world), w' (body) and eta''.
template <class D>
Eigen::MatrixXd rates(const ClusterInputs& in) {
  const int vars = in.variables;
  const std::size_t nb = in.slots.size();
  VectorT<D> r1 = VectorT<D>::Zero(in.size);  // f - M u'0, then + G^T lambda0
  std::vector<jacobian_seeds::SeededState<D>> own(nb);
  std::vector<Matrix3T<D>> rot(nb);
  std::vector<BodyMotionT<D>> motion(nb);
  std::vector<flexible_cluster::SlotMapT<D>> map(nb);
  for (std::size_t s = 0; s < nb; ++s) {
    const Slot& slot = in.slots[s];
    if (slot.flexible >= 0) continue;
    const Eigen::Index at = in.start[s];
    if (slot.first < 0) {
      motion[s] = jacobian_seeds::constant_motion<D>(slot.fixed);
      continue;
    }
    own[s] = jacobian_seeds::seeded_state<D>(slot.numbers, slot.first, vars);
    rot[s] = rotation_matrix<D>(own[s].q);
    motion[s] = {own[s].r, rot[s], own[s].v, rot[s] * own[s].w};
    Vector3T<D> force, torque;
    for (int k = 0; k < 3; ++k) {
      force[k] = dual<D>(slot.wrench.value[k], slot.wrench.derivatives, k);
      torque[k] = dual<D>(slot.wrench.value[3 + k], slot.wrench.derivatives, 3 + k);
    }
    const Vector3T<D> spin = own[s].w.cross(Vector3T<D>(as_scalar<D>(slot.inertia) * own[s].w));
    const Eigen::Vector3d a0 = in.u_rate.segment<3>(at), alpha0 = in.u_rate.segment<3>(at + 3);
    r1.template segment<3>(at) = force - (slot.mass * a0).cast<D>();
    r1.template segment<3>(at + 3) = torque - rot[s] * spin -
                                     rot[s] * Vector3T<D>(as_scalar<D>(slot.inertia) * Vector3T<D>(rot[s].transpose() * alpha0.cast<D>()));
  }
  std::vector<FlexibleEval<D>> flex(in.members.size());
  for (std::size_t i = 0; i < in.members.size(); ++i) {
    const Member& mb = in.members[i];
    const FloatingFrameData& d = *mb.body->data;
    const int ne = d.modes();
    FlexibleEval<D>& e = flex[i];
    e.frame = jacobian_seeds::seeded_modes<D>(mb.frame, mb.eta, mb.eta_rate, mb.first, vars);
    e.r = rotation_matrix<D>(e.frame.q);
    e.v_b = e.r.transpose() * e.frame.v;
    const VectorT<D> q = flexible_dynamics::generalised_force<D>(d, e.r, in.gravity, e.frame.eta, [&](int k, Vector3T<D>& force, Vector3T<D>& torque) {
      const AppliedWrench& w = mb.wrench[static_cast<std::size_t>(k + 1)];
      for (int c = 0; c < 3; ++c) {
        force[c] = dual<D>(w.value[c], w.derivatives, c);
        torque[c] = dual<D>(w.value[3 + c], w.derivatives, 3 + c);
      }
    });
    MatrixT<D> m;
    const VectorT<D> rhs = flexible_dynamics::balance<D>(d, mb.body->damping, e.v_b, e.frame.w, e.frame.eta, e.frame.eta_rate, q, m);
    r1.segment(in.block[i], 6 + ne) = rhs - m * in.u_rate.segment(in.block[i], 6 + ne).cast<D>();
  }
  for (std::size_t s = 0; s < nb; ++s) {
    const Slot& slot = in.slots[s];
    if (slot.flexible < 0) continue;
    const Member& mb = in.members[static_cast<std::size_t>(slot.flexible)];
    const FlexibleEval<D>& e = flex[static_cast<std::size_t>(slot.flexible)];
    const FloatingFrameData& d = *mb.body->data;
    map[s] = flexible_cluster::slot_map<D>(d, e.r, e.v_b, e.frame.w, e.frame.eta, e.frame.eta_rate, slot.node);
    if (slot.node < 0) {
      motion[s] = {e.frame.r, e.r, e.frame.v, e.r * e.frame.w};
      continue;
    }
    const flexible_dynamics::NodeWorldT<D> n =
        flexible_dynamics::node_world<D>(d, slot.node, e.frame.eta, e.frame.eta_rate, e.frame.r, e.frame.v, e.frame.q, e.r, e.frame.w);
    motion[s] = {n.position, rotation_matrix<D>(n.quat), n.velocity, n.omega};
  }
  // G = J T and b = bias + J gamma.
  MatrixT<D> g = MatrixT<D>::Zero(in.rows, in.size);
  VectorT<D> b(in.rows);
  std::array<ConstraintRowT<D>, max_joint_rows> rows;
  for (const ClusterInputs::Joint& j : in.joints) {
    auto side_motion = [&](int s, const BodyMotion& ground) {
      return s >= 0 ? motion[static_cast<std::size_t>(s)] : jacobian_seeds::constant_motion<D>(ground);
    };
    evaluate_constraint<D>(*j.geometry, side_motion(j.a, j.ground_a), side_motion(j.b, j.ground_b), in.t, rows.data());
    for (int k = 0; k < j.rows; ++k) {
      const ConstraintRowT<D>& row = rows[static_cast<std::size_t>(k)];
      const int r = j.first_row + k;
      b[r] = row.bias;
      for (int side = 0; side < 2; ++side) {
        const int s = side == 0 ? j.a : j.b;
        if (s < 0) continue;
        const Eigen::Matrix<D, 6, 1> jr = row.j.template segment<6>(6 * side);
        const auto at = in.start[static_cast<std::size_t>(s)];
        if (in.slots[static_cast<std::size_t>(s)].flexible < 0) {
          g.row(r).template segment<6>(at) += jr.transpose();
        } else {
          const flexible_cluster::SlotMapT<D>& m = map[static_cast<std::size_t>(s)];
          g.row(r).segment(at, m.t.cols()) += jr.transpose() * m.t;
          b[r] += jr.dot(m.gamma);
        }
      }
    }
  }
  r1 += g.transpose() * in.lambda.cast<D>();
  const VectorT<D> r2 = -(g * in.u_rate.cast<D>() + b);
  const Eigen::MatrixXd d1 = derivatives_of<D>(r1, vars), d2 = derivatives_of<D>(r2, vars);
  const Eigen::MatrixXd g_value = g.unaryExpr([](const D& x) { return x.value(); });
  // W x, block by block at the values.
  std::vector<Eigen::LDLT<Eigen::MatrixXd>> mass(in.members.size());
  for (std::size_t i = 0; i < in.members.size(); ++i)
    mass[i].compute(flexible_dynamics::mass_matrix<double>(*in.members[i].body->data, in.members[i].eta));
  auto apply_w = [&](const Eigen::MatrixXd& x) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), x.cols());
    for (std::size_t s = 0; s < nb; ++s) {
      const Slot& slot = in.slots[s];
      if (slot.flexible >= 0) continue;
      const Eigen::Index at = in.start[s];
      out.middleRows<3>(at) = slot.inv_mass * x.middleRows<3>(at);
      out.middleRows<3>(at + 3) = slot.inv_inertia * x.middleRows<3>(at + 3);
    }
    for (std::size_t i = 0; i < in.members.size(); ++i)
      out.middleRows(in.block[i], mass[i].rows()) = mass[i].solve(x.middleRows(in.block[i], mass[i].rows()));
    return out;
  };
  const Eigen::MatrixXd w_gt = apply_w(g_value.transpose());
  const Eigen::MatrixXd w_d1 = apply_w(d1);
  Eigen::MatrixXd d_lambda = d2 - g_value * w_d1;
  flexible_cluster::solve_rows(Eigen::MatrixXd(g_value * w_gt), d_lambda);
  const Eigen::MatrixXd du = w_d1 + w_gt * d_lambda;
  // The rates from u' = u'0 + du'.
  VectorT<D> u_rate(in.size);
  for (Eigen::Index k = 0; k < in.size; ++k) u_rate[k] = D(in.u_rate[k], du.row(k).transpose());
  std::vector<VectorT<D>> out;
  for (std::size_t s = 0; s < nb; ++s) {
    const Slot& slot = in.slots[s];
    if (slot.flexible >= 0 || slot.first < 0) continue;
    const Eigen::Index at = in.start[s];
    VectorT<D> o(6);
    o << u_rate.template segment<3>(at), rot[s].transpose() * Vector3T<D>(u_rate.template segment<3>(at + 3));
    out.push_back(o);
  }
  for (std::size_t i = 0; i < in.members.size(); ++i) {
    const FlexibleEval<D>& e = flex[i];
    const int ne = in.members[i].body->data->modes();
    const auto xi = u_rate.segment(in.block[i], 6 + ne);
    VectorT<D> o(6 + ne);
    o << e.r * Vector3T<D>(Vector3T<D>(xi.template head<3>()) + e.frame.w.cross(e.v_b)), xi.tail(3 + ne);
    out.push_back(o);
  }
  Eigen::Index total = 0;
  for (const VectorT<D>& o : out) total += o.size();
  Eigen::MatrixXd result(total, vars);
  Eigen::Index row = 0;
  for (const VectorT<D>& o : out) {
    result.middleRows(row, o.size()) = derivatives_of<D>(o, vars);
    row += o.size();
  }
  return result;
}

}  // namespace

void MultibodySystem::flexible_cluster_jacobian(int c, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& dydt,
                                                const std::function<void(int, Vector6d&, WrenchParts&)>& wrench_of,
                                                const std::function<void(Eigen::Index, Eigen::Index, int, const double*)>& write) const {
  const Constraints& k = *constraints_;
  const RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const std::vector<int>& bodies = rc.bodies();
  const FlexibleSlots* fs = k.flexible_slots_of(c);
  ClusterInputs in;
  in.t = t;
  in.gravity = gravity_;
  jacobian_seeds::Variables vars;
  const std::size_t nb = bodies.size();
  in.slots.resize(nb);
  in.start.resize(nb);
  // The slots and members, their own numbers the first variables.
  for (std::size_t s = 0; s < nb; ++s) {
    Slot& slot = in.slots[s];
    const int i = bodies[s];
    const auto bi = static_cast<std::size_t>(i);
    if (fs && fs->owner[s] >= 0) {
      slot.flexible = fs->owner[s];
      slot.node = fs->node[s];
      in.start[s] = fs->start[s];
      continue;
    }
    in.start[s] = fs ? fs->start[s] : static_cast<Eigen::Index>(6 * s);
    slot.inv_mass = rc.inv_mass[s];  // set by the right-hand side's solve just before
    slot.inv_inertia = rc.inv_inertia[s];
    if (compiled_->driver_of_body[bi] >= 0) {
      slot.fixed = motion_at(i);
      continue;
    }
    slot.numbers = jacobian_seeds::body_numbers(y, layout_, i);
    slot.first = vars.of(jacobian_seeds::state_index(layout_, i, 0));
    for (int q = 1; q < body_states; ++q) vars.of(jacobian_seeds::state_index(layout_, i, q));
    const BodyLaw& law = body_law(bi);
    slot.mass = law.mass;
    slot.inertia = law.inertia;
  }
  in.size = fs ? fs->size : static_cast<Eigen::Index>(6 * nb);
  if (fs)
    for (std::size_t i = 0; i < fs->flexible.size(); ++i) {
      const auto f = static_cast<std::size_t>(fs->flexible[i]);
      const FlexibleBody& fb = model().flexible[f];
      const FlexibleAt at = flexible_at(fb, layout_, compiled_->flexible_tail[f], y);
      Member& mb = in.members.emplace_back();
      mb.body = &fb;
      mb.frame = jacobian_seeds::body_numbers(y, layout_, fb.frame);
      mb.eta = at.eta;
      mb.eta_rate = at.eta_rate;
      mb.first = vars.of(jacobian_seeds::state_index(layout_, fb.frame, 0));
      for (int q = 1; q < body_states; ++q) vars.of(jacobian_seeds::state_index(layout_, fb.frame, q));
      for (int q = 0; q < 2 * at.ne; ++q) vars.of(at.tail + q);
      in.block.push_back(fs->block[i]);
    }
  // The applied wrenches and what they read.
  WrenchParts parts;
  std::vector<std::pair<AppliedWrench*, WrenchParts>> read;
  for (std::size_t s = 0; s < nb; ++s)
    if (in.slots[s].flexible < 0 && in.slots[s].first >= 0) {
      wrench_of(bodies[s], in.slots[s].wrench.value, parts);
      for (const auto& [col, d] : parts) vars.of(col);
      read.emplace_back(&in.slots[s].wrench, parts);
    }
  for (Member& mb : in.members) {
    mb.wrench.resize(1 + mb.body->nodes.size());
    for (std::size_t q = 0; q < mb.wrench.size(); ++q) {
      wrench_of(q == 0 ? mb.body->frame : mb.body->nodes[q - 1], mb.wrench[q].value, parts);
      for (const auto& [col, d] : parts) vars.of(col);
      read.emplace_back(&mb.wrench[q], parts);
    }
  }
  in.variables = vars.count();
  for (auto& [w, p] : read) w->derivatives = vars.gather(p, 6);
  for (const ClusterJoint& cj : rc.joints()) {
    const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
    ClusterInputs::Joint& out = in.joints.emplace_back();
    out.geometry = &geometry_of(j);
    out.a = cj.a;
    out.b = cj.b;
    if (cj.a < 0) out.ground_a = motion_at(j.a);
    if (cj.b < 0) out.ground_b = motion_at(j.b);
    out.first_row = cj.first_row;
    out.rows = cj.rows;
  }
  in.rows = rc.row_count();
  in.lambda = k.lambda[static_cast<std::size_t>(c)];
  // u'0 from the rates just evaluated.
  in.u_rate.resize(in.size);
  for (std::size_t s = 0; s < nb; ++s) {
    if (in.slots[s].flexible >= 0) continue;
    const int i = bodies[s];
    in.u_rate.segment<3>(in.start[s]) = dydt.segment<3>(layout_.velocity(i));
    in.u_rate.segment<3>(in.start[s] + 3) = rot_[static_cast<std::size_t>(i)] * dydt.segment<3>(layout_.angular_velocity(i));
  }
  for (std::size_t i = 0; i < in.members.size(); ++i) {
    const Member& mb = in.members[i];
    const int frame = mb.body->frame, ne = mb.body->data->modes();
    const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(frame)];
    const Eigen::Vector3d w = y.segment<3>(layout_.angular_velocity(frame)), v_b = r.transpose() * y.segment<3>(layout_.velocity(frame));
    const Eigen::Index at = in.block[i], tail = layout_.tail(compiled_->flexible_tail[static_cast<std::size_t>(fs->flexible[i])]);
    in.u_rate.segment<3>(at) = r.transpose() * dydt.segment<3>(layout_.velocity(frame)) - w.cross(v_b);
    in.u_rate.segment<3>(at + 3) = dydt.segment<3>(layout_.angular_velocity(frame));
    in.u_rate.segment(at + 6, ne) = dydt.segment(tail + ne, ne);
  }

  const Eigen::MatrixXd d = in.variables <= stack_variables ? rates<StackDual>(in) : rates<HeapDual>(in);
  // The rows they go to, in rates()'s order.
  std::vector<std::pair<Eigen::Index, int>> rows;  // (first row in y, count)
  for (std::size_t s = 0; s < nb; ++s)
    if (in.slots[s].flexible < 0 && in.slots[s].first >= 0) {
      rows.emplace_back(layout_.velocity(bodies[s]), 3);
      rows.emplace_back(layout_.angular_velocity(bodies[s]), 3);
    }
  if (fs)
    for (std::size_t i = 0; i < fs->flexible.size(); ++i) {
      const auto f = static_cast<std::size_t>(fs->flexible[i]);
      const int frame = model().flexible[f].frame, ne = model().flexible[f].data->modes();
      rows.emplace_back(layout_.velocity(frame), 3);
      rows.emplace_back(layout_.angular_velocity(frame), 3);
      rows.emplace_back(layout_.tail(compiled_->flexible_tail[f]) + ne, ne);
    }
  for (int v = 0; v < in.variables; ++v) {
    const double* column = d.col(v).data();
    for (const auto& [row, count] : rows) {
      write(vars.cols[static_cast<std::size_t>(v)], row, count, column);
      column += count;
    }
  }
}

}  // namespace mbsflow
