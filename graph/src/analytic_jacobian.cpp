// The analytic Jacobian of the multibody right-hand side: the wrench of each spring,
// bushing and compliant kinematic joint (with its motor and limit stops) differentiated
// in forward-mode dual numbers with respect to the 26 state numbers of its two bodies
// (force_laws.hpp and kinematic_joint_wrench.hpp, the arithmetic the right-hand side
// runs), then assembled body by body along the body graph with the chain rule through
//   v' = F / m,  w' = J^-1 (R(q)^T T - w x J w),  q' = q (x) (0, w) / 2,  r' = v.
// The bodies of a rigid cluster get their rates' derivatives through the cluster's
// reactions (cluster_jacobian.cpp); a flexible body's frame, modes and nodes through its
// equations in dual numbers (flexible_jacobian.cpp), and where rigid joints hold it
// through its cluster's solve in generalised velocities (flexible_cluster_jacobian.cpp).
// Exact up to rounding, so Newton converges at its own rate, and no right-hand-side call
// is spent on differences.
#include <algorithm>
#include <atomic>
#include <type_traits>

#include "flexible_jacobian.hpp"
#include "flexible_state.hpp"
#include "jacobian_seeds.hpp"
#include "jacobian_slots.hpp"
#include "kinematic_joint_wrench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {
namespace {

using namespace jacobian_seeds;
using jacobian_slots::SlotCursor;
using jacobian_slots::SlotWriter;

// Derivative rows of a dual vector, columns first..first+12.
template <int Rows, class D>
Eigen::Matrix<double, Rows, body_states> derivatives(const Eigen::Matrix<D, Rows, 1>& v, int first) {
  Eigen::Matrix<double, Rows, body_states> d;
  for (int r = 0; r < Rows; ++r) d.row(r) = v[r].derivatives().template segment<body_states>(first).transpose();
  return d;
}

}  // namespace

namespace {
bool no_jacobian(std::string* why, std::string reason) {
  if (why) *why = std::move(reason);
  return false;
}
}  // namespace

bool has_analytic_jacobian(const Model& m, std::string* why) {
  for (const auto& e : m.force_elements)
    if (!e->constant_wrench()) return no_jacobian(why, "the model has user force elements");
  return true;
}

bool MultibodySystem::has_analytic_jacobian(std::string* why) const {
  if (active_ != layout_.bodies) return no_jacobian(why, "the system is a submodel (its ghost bodies' states come from other submodels)");
  if (!mbsflow::has_analytic_jacobian(model(), why)) return false;
  for (const auto& e : compiled_->elements)  // added after construction
    if (!e->constant_wrench()) return no_jacobian(why, "the model has user force elements");
  return true;
}

void MultibodySystem::jacobian(double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac, const ParallelFor& parallel,
                               bool velocity_columns) {
  if (std::string why; !has_analytic_jacobian(&why)) throw InputError("MultibodySystem::jacobian: no analytic Jacobian: " + why);
  // The rates themselves where rigid clusters need them (their accelerations, multipliers
  // and factors, cluster_jacobian.cpp); the kinematics and joint forces in any case (the
  // torques, whose value w' depends on through R(q)^T).
  const int n_clusters = clusters();
  Eigen::VectorXd rates;
  if (n_clusters > 0) {
    rates.resize(y.size());
    rhs(t, y, rates);
  } else {
    update_kinematics(t, y);
    compute_joint_forces();
  }
  // Per cluster and body slot: the rate blocks under the applied forces, which the
  // cluster's part turns into its bodies' rows.
  std::vector<std::vector<RateBlocks>> unconstrained(static_cast<std::size_t>(n_clusters));
  for (int c = 0; c < n_clusters; ++c) unconstrained[static_cast<std::size_t>(c)].resize(cluster_bodies(c).size());
  std::fill_n(jac.valuePtr(), jac.nonZeros(), 0.0);
  const Eigen::Index n = layout_.bodies;
  const std::vector<FlexibleBody>& flexible = model().flexible;
  // A kinematics index whose state is a variable: not ground (index n), not driven.
  auto free = [&](int k) { return k < n && compiled_->driver_of_body[static_cast<std::size_t>(k)] < 0; };
  auto constant_frame = [&]<class D>(std::type_identity<D>, int k) {
    BodyFrameT<D> f;
    f.rot = rot_[static_cast<std::size_t>(k)].cast<D>();
    f.pos = pos_.col(k).cast<D>();
    f.vel = vel_.col(k).cast<D>();
    f.omega = omega_.col(k).cast<D>();
    f.quat = quat_.col(k).cast<D>();
    return f;
  };
  // A flexible body's node (follows_frame) and its slot k there. Its numbers are those it
  // follows its frame and the modes with (its own in y are where the last step left it),
  // and what reads them reads the frame and the modes through node_maps[f][k].
  std::vector<int> node_slot(flexible.empty() ? 0 : static_cast<std::size_t>(n), -1);
  std::vector<FlexibleAt> flexible_now;  // each flexible body's coordinates at y
  std::vector<std::vector<Eigen::MatrixXd>> node_maps(flexible.size());
  for (std::size_t f = 0; f < flexible.size(); ++f) {
    const FlexibleAt& at = flexible_now.emplace_back(flexible_at(flexible[f], layout_, compiled_->flexible_tail[f], y));
    const BodyNumbers frame = body_numbers(y, layout_, flexible[f].frame);
    for (std::size_t k = 0; k < flexible[f].nodes.size(); ++k) {
      node_slot[static_cast<std::size_t>(flexible[f].nodes[k])] = static_cast<int>(k);
      node_maps[f].push_back(flexible_jacobian::node_map(at.d, static_cast<int>(k), frame, at.eta, at.eta_rate));
    }
  }
  auto is_node = [&](int b) { return b < n && follows_frame(static_cast<std::size_t>(b)); };
  auto numbers = [&](int b) -> BodyNumbers {
    if (!is_node(b)) return body_numbers(y, layout_, b);
    const auto bb = static_cast<std::size_t>(b);
    BodyNumbers s;
    s << pos_.col(b), quat_.col(b), vel_.col(b), rot_[bb].transpose() * omega_.col(b);
    return s;
  };

  // d (wrench of joint k) / d (states of its body1, then of its body2).
  using JointDerivatives = Eigen::Matrix<double, 9, 2 * body_states>;
  jacobian_scratch_.resize(compiled_->joints.size() * JointDerivatives::SizeAtCompileTime);
  auto joint_derivatives = [&](std::size_t k) {
    return Eigen::Map<JointDerivatives>(jacobian_scratch_.data() + k * JointDerivatives::SizeAtCompileTime);
  };
  // Each joint reads the kinematics and writes its own derivatives: the loop may be split.
  // D: Dual (every state number of its two bodies a variable) or PositionDual (their
  // positions and orientations alone, the velocity columns zero).
  const auto differentiate_joints = [&]<class D>(std::type_identity<D> type, std::size_t begin, std::size_t end) {
    constexpr int per_body = D::DerType::SizeAtCompileTime / 2;
    for (std::size_t k = begin; k < end; ++k) {
      const CompiledJoint& j = compiled_->joints[k];
      const BodyFrameT<D> a = free(j.a) ? seeded_frame<D>(numbers(j.a), 0) : constant_frame(type, j.a);
      const BodyFrameT<D> b = free(j.b) ? seeded_frame<D>(numbers(j.b), per_body) : constant_frame(type, j.b);
      Eigen::Matrix<D, 9, 1> out;
      if (j.kinematic >= 0) {  // compliant, or the limit stops and effort motor of a rigid one
        out.setZero();
        if (j.applies_force) kinematic_joint_wrench<D>(law_of(j), j.rigid, geometry_of(j), motion(a), motion(b), t, out, nullptr);
      } else {
        compliant_joint_wrench<D>(law_of(j), tables_of(j), a, b, out);
      }
      auto d = joint_derivatives(k);
      if constexpr (per_body == body_states) {
        for (int r = 0; r < 9; ++r) d.row(r) = out[r].derivatives().transpose();
      } else {
        d.setZero();
        for (int r = 0; r < 9; ++r) {
          d.row(r).template head<per_body>() = out[r].derivatives().template head<per_body>().transpose();
          d.row(r).template segment<per_body>(body_states) = out[r].derivatives().template tail<per_body>().transpose();
        }
      }
    }
  };
  const auto differentiate = [&](std::size_t begin, std::size_t end) {
    if (velocity_columns)
      differentiate_joints(std::type_identity<Dual>{}, begin, end);
    else
      differentiate_joints(std::type_identity<PositionDual>{}, begin, end);
  };
  if (parallel)
    parallel(compiled_->joints.size(), differentiate);
  else
    differentiate(0, compiled_->joints.size());

  SlotWriter slots(jac, jacobian_slots_.outer, jacobian_slots_.slots);
  // A body's wrench derivatives, one per thread: per body read, d (force, torque) / d (its
  // state); per flexible body read through one of its nodes, d (force, torque) / d (eta, eta').
  struct Scratch {
    std::vector<std::pair<int, Block6>> blocks;
    std::vector<std::pair<int, Eigen::Matrix<double, 6, Eigen::Dynamic>>> tails;
  };
  Scratch serial;
  auto block_of = [](Scratch& s, int body) -> Block6& {
    for (auto& [b, m] : s.blocks)
      if (b == body) return m;
    return s.blocks.emplace_back(body, Block6::Zero()).second;
  };
  auto tail_of = [&](Scratch& s, int f) -> Eigen::Matrix<double, 6, Eigen::Dynamic>& {
    for (auto& [g, m] : s.tails)
      if (g == f) return m;
    return s.tails.emplace_back(f, Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, 2 * flexible[static_cast<std::size_t>(f)].data->modes())).second;
  };
  // d (force, torque on body i, world) / d (the states it reads) into blocks and tails: its
  // loads (through its own numbers, returned) and its joints, a node's read through its
  // frame and modes.
  auto wrench_blocks = [&](Scratch& s, Eigen::Index i) {
    auto& blocks = s.blocks;
    blocks.clear();
    s.tails.clear();
    const auto bi = static_cast<std::size_t>(i);
    const SeededState<BodyDual> own = seeded_state<BodyDual>(numbers(static_cast<int>(i)), 0);
    const Matrix3T<BodyDual> rot = rotation_matrix<BodyDual>(own.q);
    // Loads: through the orientation, and a damping load through the velocities too.
    Vector3T<BodyDual> load_force = Vector3T<BodyDual>::Zero(), load_torque = Vector3T<BodyDual>::Zero();
    for (int p = compiled_->load_start[bi]; p < compiled_->load_start[bi + 1]; ++p) {
      const Load& l = model().loads[static_cast<std::size_t>(compiled_->load_index[static_cast<std::size_t>(p)])];
      add_load<BodyDual>(l, evaluate(l.function, t).value, rot, own.v, own.w, load_force, load_torque);
    }
    Block6& self = block_of(s, static_cast<int>(i));
    self.topRows<3>() = derivatives<3>(load_force, 0);
    self.bottomRows<3>() = derivatives<3>(load_torque, 0);
    // Joints: body1 gets minus the force and the torque rows 3-5, body2 the force and rows 6-8.
    for (int p = compiled_->incidence_start[bi]; p < compiled_->incidence_start[bi + 1]; ++p) {
      const int code = compiled_->incidence[static_cast<std::size_t>(p)];
      const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(code / 2)];
      const auto d = joint_derivatives(static_cast<std::size_t>(code / 2));
      const bool body2 = code & 1;
      for (int side = 0; side < 2; ++side) {
        const int other = side == 0 ? j.a : j.b;
        if (!free(other)) continue;
        Block6& m = block_of(s, other);
        const auto cols = d.middleCols<body_states>(side * body_states);
        if (body2)
          m.topRows<3>() += cols.topRows<3>();
        else
          m.topRows<3>() -= cols.topRows<3>();
        m.bottomRows<3>() += cols.middleRows<3>(body2 ? 6 : 3);
      }
    }
    for (std::size_t p = 0, count = blocks.size(); p < count; ++p) {
      const int b = blocks[p].first;
      if (!is_node(b)) continue;
      const int f = compiled_->flexible_of_body[static_cast<std::size_t>(b)], k = node_slot[static_cast<std::size_t>(b)];
      const Eigen::Matrix<double, 6, Eigen::Dynamic> through = blocks[p].second * node_maps[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
      blocks[p].first = -1;
      block_of(s, flexible[static_cast<std::size_t>(f)].frame) += through.leftCols<body_states>();
      tail_of(s, f) += through.rightCols(through.cols() - body_states);
    }
    std::erase_if(blocks, [](const auto& e) { return e.first < 0; });
    return own;
  };
  auto tail_column = [&](int f, Eigen::Index c) { return layout_.tail(compiled_->flexible_tail[static_cast<std::size_t>(f)]) + c; };
  // q' = q (x) (0, w) / 2 and r' = v of body i, its numbers seeded in own.
  auto kinematic_rows = [&](auto& slots, Eigen::Index i, const SeededState<BodyDual>& own) {
    const Eigen::Matrix<double, 4, body_states> q_rate = derivatives<4>(quaternion_rate<BodyDual>(own.q, own.w), 0);
    for (int c = 0; c < 4; ++c) std::copy_n(q_rate.col(3 + c).data(), 4, slots.at(layout_.orientation(i), layout_.orientation(i) + c, 4));
    for (int c = 0; c < 3; ++c) std::copy_n(q_rate.col(10 + c).data(), 4, slots.at(layout_.orientation(i), layout_.angular_velocity(i) + c, 4));
    for (int k = 0; k < 3; ++k) *slots.at(layout_.position(i) + k, layout_.velocity(i) + k) = 1.0;
  };
  // The clusters whose rates are solved in generalised velocities here
  // (flexible_cluster_jacobian.cpp): those that hold flexible bodies, and those whose
  // bodies read a flexible body's modes (found below).
  std::vector<char> generalised(static_cast<std::size_t>(n_clusters), 0);
  for (const FlexibleBody& fb : flexible)
    if (const int c = n_clusters > 0 ? cluster_of(fb.frame) : -1; c >= 0) generalised[static_cast<std::size_t>(c)] = 1;

  // Body i's rate rows: through `slots`, a SlotWriter or (split over threads) a SlotCursor.
  const auto body_rows = [&](auto& slots, Scratch& scratch, Eigen::Index i) {
    const auto bi = static_cast<std::size_t>(i);
    if (!free(static_cast<int>(i))) return;  // a driven body's rates do not depend on the state
    if (!compiled_->flexible_of_body.empty() && compiled_->flexible_of_body[bi] >= 0) return;  // flexible_rows below
    const int cluster = n_clusters > 0 ? cluster_of(static_cast<int>(i)) : -1;
    if (cluster >= 0 && generalised[static_cast<std::size_t>(cluster)]) {  // its rates come with its cluster's, below
      kinematic_rows(slots, i, seeded_state<BodyDual>(numbers(static_cast<int>(i)), 0));
      return;
    }
    const SeededState<BodyDual> own = wrench_blocks(scratch, i);
    const Matrix3T<BodyDual> rot = rotation_matrix<BodyDual>(own.q);
    // w' = J^-1 (R^T T - w x J w): the torque's derivatives through J^-1 R^T; R(q) and the
    // gyroscopic term through the body's own quaternion and angular velocity.
    Eigen::Vector3d force, torque;
    applied_wrench(i, t, y, force, torque);
    const BodyLaw& law = body_law(bi);
    const Eigen::Matrix3d to_w = law.inv_inertia * rot_[bi].transpose();
    const Vector3T<BodyDual> w_rate = angular_acceleration<BodyDual>(rot, own.w, Vector3T<BodyDual>(torque.cast<BodyDual>()),
                                                                     law.inertia, law.inv_inertia);
    if (cluster >= 0 && !scratch.tails.empty()) generalised[static_cast<std::size_t>(cluster)] = 1;
    for (const auto& [b, m] : scratch.blocks) {
      Block6 rows;
      rows.topRows<3>() = law.inv_mass * m.template topRows<3>();
      rows.bottomRows<3>() = to_w * m.template bottomRows<3>();
      if (b == i) rows.bottomRows<3>() += derivatives<3>(w_rate, 0);
      if (cluster >= 0) {  // written with the cluster's reactions below
        const std::vector<int>& members = cluster_bodies(cluster);
        const auto slot = std::lower_bound(members.begin(), members.end(), static_cast<int>(i)) - members.begin();
        unconstrained[static_cast<std::size_t>(cluster)][static_cast<std::size_t>(slot)].emplace_back(b, rows);
        continue;
      }
      for (int c = 0; c < body_states; ++c) {
        const Eigen::Index col = state_index(layout_, b, c);
        double* v = slots.at(layout_.velocity(i), col, 3);
        double* w = slots.at(layout_.angular_velocity(i), col, 3);
        for (int r = 0; r < 3; ++r) {
          v[r] = rows(r, c);
          w[r] = rows(3 + r, c);
        }
      }
    }
    if (cluster < 0)
      for (const auto& [f, m] : scratch.tails)
        for (Eigen::Index c = 0; c < m.cols(); ++c) {
          const Eigen::Vector3d v_col = law.inv_mass * m.col(c).template head<3>(), w_col = to_w * m.col(c).template tail<3>();
          std::copy_n(v_col.data(), 3, slots.at(layout_.velocity(i), tail_column(f, c), 3));
          std::copy_n(w_col.data(), 3, slots.at(layout_.angular_velocity(i), tail_column(f, c), 3));
        }
    kinematic_rows(slots, i, own);
  };
  // Split over threads where the places of every body's writes are known from an earlier
  // call (each body replays its own, from its first) and nothing is shared: no rigid
  // clusters (their reactions gather their bodies' rows), no flexible bodies. The values
  // are the serial loop's, whatever the split.
  std::vector<int>& marks = jacobian_slots_.body_marks;
  bool split = parallel && n_clusters == 0 && flexible.empty() && slots.replaying() && slots.position() == 0 &&
               marks.size() == static_cast<std::size_t>(n) + 1;
  if (split) {
    std::atomic<bool> failed = false;
    parallel(static_cast<std::size_t>(n), [&](std::size_t begin, std::size_t end) {
      Scratch scratch;
      for (std::size_t i = begin; i < end && !failed; ++i) {
        SlotCursor cursor(jac, jacobian_slots_.slots, static_cast<std::size_t>(marks[i]));
        body_rows(cursor, scratch, static_cast<Eigen::Index>(i));
        if (cursor.failed() || cursor.position() != static_cast<std::size_t>(marks[i + 1])) failed = true;
      }
    });
    if (failed) {  // the places kept do not fit: written afresh, by search
      std::fill_n(jac.valuePtr(), jac.nonZeros(), 0.0);
      slots.restart();
      split = false;
    } else {
      slots.skip_to(static_cast<std::size_t>(marks.back()));
    }
  }
  if (!split) {
    marks.assign(static_cast<std::size_t>(n) + 1, 0);
    for (Eigen::Index i = 0; i < n; ++i) {
      marks[static_cast<std::size_t>(i)] = static_cast<int>(slots.position());
      body_rows(slots, serial, i);
    }
    marks.back() = static_cast<int>(slots.position());
  }

  // The applied wrench on body b (world force, torque) and its derivatives by the state
  // numbers it reads, a node's read through its frame and modes.
  auto wrench_of = [&](int b, Eigen::Matrix<double, 6, 1>& value, WrenchParts& parts) {
    wrench_blocks(serial, b);
    parts.clear();
    for (const auto& [r, m] : serial.blocks)
      for (int c = 0; c < body_states; ++c) parts.emplace_back(state_index(layout_, r, c), m.col(c));
    for (const auto& [g, m] : serial.tails)
      for (Eigen::Index c = 0; c < m.cols(); ++c) parts.emplace_back(tail_column(g, c), m.col(c));
    Eigen::Vector3d force, torque;
    applied_wrench(b, t, y, force, torque);
    value << force, torque;
  };

  // Each flexible body: its frame's and modes' rates in dual numbers over the frame's
  // numbers, the modes and whatever its frame and nodes read (with its cluster's, below,
  // where rigid joints hold it); its nodes' position and orientation rates through
  // node_maps.
  for (std::size_t f = 0; f < flexible.size(); ++f) {
    const FlexibleBody& fb = flexible[f];
    const int i = fb.frame, ne = fb.data->modes();
    const Eigen::Index tail = tail_column(static_cast<int>(f), 0);
    kinematic_rows(slots, i, seeded_state<BodyDual>(numbers(i), 0));
    if (n_clusters == 0 || cluster_of(i) < 0) {
      Variables vars;  // the frame's numbers, eta, eta', then what the wrenches read
      for (int c = 0; c < body_states; ++c) vars.of(state_index(layout_, i, c));
      for (int c = 0; c < 2 * ne; ++c) vars.of(tail + c);
      // Each slot's (frame, then nodes) wrench: its value and, per variable, its derivative.
      const std::size_t slots_count = 1 + fb.nodes.size();
      std::vector<WrenchParts> read(slots_count);
      std::vector<flexible_jacobian::SlotWrench> wrench(slots_count);
      for (std::size_t s = 0; s < slots_count; ++s) {
        wrench_of(s == 0 ? i : fb.nodes[s - 1], wrench[s].value, read[s]);
        for (const auto& [col, d] : read[s]) vars.of(col);
      }
      const int variables = vars.count();
      for (std::size_t s = 0; s < slots_count; ++s) wrench[s].derivatives = vars.gather(read[s], 6);
      const FlexibleAt& at = flexible_now[f];
      const Eigen::MatrixXd d =
          flexible_jacobian::rate_derivatives(fb, gravity_, body_numbers(y, layout_, i), at.eta, at.eta_rate, wrench, variables);
      for (int c = 0; c < variables; ++c) {  // d's column-major: each variable's rows in a run
        const double* column = d.col(c).data();
        const Eigen::Index col = vars.cols[static_cast<std::size_t>(c)];
        std::copy_n(column + 4, 3, slots.at(layout_.velocity(i), col, 3));
        std::copy_n(column + 7, 3, slots.at(layout_.angular_velocity(i), col, 3));
        std::copy_n(column + 10, ne, slots.at(tail + ne, col, ne));
      }
    }
    for (int k = 0; k < ne; ++k) *slots.at(tail + k, tail + ne + k) = 1.0;
    // A node's r' = its velocity, q' = q (x) (0, w) / 2 at its numbers: through its frame's
    // orientation, velocity and angular velocity and the modes (not the frame's position).
    for (std::size_t k = 0; k < fb.nodes.size(); ++k) {
      const int b = fb.nodes[k];
      const Eigen::MatrixXd& map = node_maps[f][k];
      const SeededState<BodyDual> node = seeded_state<BodyDual>(numbers(b), 0);
      const Eigen::MatrixXd q_rate = derivatives<4>(quaternion_rate<BodyDual>(node.q, node.w), 0) * map;
      for (Eigen::Index c = 3; c < map.cols(); ++c) {
        const Eigen::Index col = c < body_states ? state_index(layout_, i, static_cast<int>(c)) : tail + c - body_states;
        const Eigen::Vector3d r_rate = map.col(c).segment<3>(7);
        const Eigen::Vector4d o_rate = q_rate.col(c);
        std::copy_n(r_rate.data(), 3, slots.at(layout_.position(b), col, 3));
        std::copy_n(o_rate.data(), 4, slots.at(layout_.orientation(b), col, 4));
      }
    }
  }

  for (int c = 0; c < n_clusters; ++c) {
    if (generalised[static_cast<std::size_t>(c)]) {
      flexible_cluster_jacobian(c, t, y, rates, wrench_of, [&](Eigen::Index col, Eigen::Index row, int count, const double* values) {
        std::copy_n(values, count, slots.at(row, col, count));
      });
      continue;
    }
    const std::vector<int>& members = cluster_bodies(c);
    cluster_jacobian(c, t, y, rates, unconstrained[static_cast<std::size_t>(c)],
                     [&](int b, int k, const Eigen::VectorXd& d) {
                       const Eigen::Index col = state_index(layout_, b, k);
                       for (std::size_t s = 0; s < members.size(); ++s) {
                         const int i = members[s];
                         if (!free(i)) continue;
                         double* v = slots.at(layout_.velocity(i), col, 3);
                         double* w = slots.at(layout_.angular_velocity(i), col, 3);
                         for (int r = 0; r < 3; ++r) {
                           v[r] = d[static_cast<Eigen::Index>(6 * s) + r];
                           w[r] = d[static_cast<Eigen::Index>(6 * s) + 3 + r];
                         }
                       }
                     });
  }
}

}  // namespace mbsflow
