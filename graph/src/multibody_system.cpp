#include "mbsflow/graph/multibody_system.hpp"

#include <algorithm>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/simd.hpp"
#include "body_csr.hpp"
#include "multibody_constraints.hpp"
#include "force_laws.hpp"
#include "lanes.hpp"
#include "rotation.hpp"
#include "shared_laws.hpp"
#include "as_eigen.hpp"

namespace mbsflow {
namespace {


// in_lane_groups with the kernel of the CPU's instruction set (simd.hpp): four lanes on
// AVX, else Lanes::width (two, SSE2).
template <int Classes, class Classify, class Single, class Sse2, class Avx>
void lane_groups_for_cpu(const int* list, std::size_t n, Classify&& classify, Single&& single, Sse2&& sse2, Avx&& avx) {
  if (simd() == Simd::avx)
    in_lane_groups<Classes, 4>(list, n, classify, single, avx);
  else
    in_lane_groups<Classes>(list, n, classify, single, sse2);
}

}  // namespace

Eigen::Matrix3d inertia_matrix(const Vec6& i) {
  Eigen::Matrix3d m;
  m << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  return m;
}

MultibodySystem::MultibodySystem(const Model& model) : MultibodySystem(model, static_cast<int>(model.bodies.size())) {}

MultibodySystem::MultibodySystem(const Model& model, int active)
    : MultibodySystem(std::make_shared<const Model>(model), active) {}

MultibodySystem::MultibodySystem(Model&& model, int active)
    : MultibodySystem(std::make_shared<const Model>(std::move(model)), active) {}

MultibodySystem::MultibodySystem(std::shared_ptr<const Model> shared, int active) : model_(std::move(shared)) {
  if (!model_) throw InputError("MultibodySystem: no model (a null shared_ptr)");
  const Model& model = *model_;
  check_model(model);
  const int n = static_cast<int>(model.bodies.size());
  layout_.bodies = n;
  active_ = std::clamp(active, 0, n);
  gravity_ = vec(model.gravity);
  // Exact sizes: growth by doubling would hold up to twice these (a million bodies).
  compiled_->joints.reserve(model.joints.size());
  DistinctIndex bodies = distinct_by_bits(model.bodies.size(), [&](std::size_t i) { return body_law_key(model.bodies[i]); });
  compiled_->body_law = std::move(bodies.of_item);
  compiled_->body_laws.reserve(bodies.first.size());
  for (int first : bodies.first) {
    const Body& b = model.bodies[static_cast<std::size_t>(first)];
    BodyLaw& c = compiled_->body_laws.emplace_back();
    c.mass = b.mass;
    c.inv_mass = 1.0 / b.mass;
    c.inertia = inertia_matrix(b.inertia);
    c.inv_inertia = c.inertia.inverse();
  }
  auto kin = [n](int body) { return body == ground ? n : body; };
  const DistinctIndex laws = distinct_by_bits(model.joints.size(), [&](std::size_t k) { return joint_law_key(model.joints[k]); });
  compiled_->laws.reserve(laws.first.size());
  for (int first : laws.first) {
    const Joint& j = model.joints[static_cast<std::size_t>(first)];
    JointLaw& c = compiled_->laws.emplace_back();
    c.spring = j.type == JointType::spring;
    c.pa = vec(j.point1);
    c.pb = vec(j.point2);
    c.qfa = vec(j.frame1).normalized();
    c.qfb = vec(j.frame2).normalized();
    c.frame1_identity = j.frame1 == Quat{1.0, 0.0, 0.0, 0.0};
    c.frame2_identity = j.frame2 == Quat{1.0, 0.0, 0.0, 0.0};
    c.rfa = rotation_matrix(c.qfa);
    c.kt = {j.stiffness[0], j.stiffness[1], j.stiffness[2]};
    c.kr = {j.stiffness[3], j.stiffness[4], j.stiffness[5]};
    c.ct = {j.damping[0], j.damping[1], j.damping[2]};
    c.cr = {j.damping[3], j.damping[4], j.damping[5]};
    c.preload_force = {j.preload[0], j.preload[1], j.preload[2]};
    c.preload_torque = {j.preload[3], j.preload[4], j.preload[5]};
    c.rest_length = j.rest_length;
  }
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& j = model.joints[k];
    CompiledJoint c;
    c.a = kin(j.body1);
    c.b = kin(j.body2);
    c.law = laws.of_item[k];
    if (j.tables.any()) {
      c.tables = static_cast<int>(compiled_->tables.size());
      compiled_->tables.push_back(j.tables.all());
    }
    compiled_->joints.push_back(c);
  }
  const int nj = static_cast<int>(model.joints.size());
  build_body_csr(static_cast<std::size_t>(n), [&](auto emit) {
    for (int k = 0; k < nj; ++k) {
      const Joint& j = model.joints[static_cast<std::size_t>(k)];
      if (j.body1 != ground) emit(j.body1, 2 * k);
      emit(j.body2, 2 * k + 1);
    }
  }, compiled_->incidence_start, compiled_->incidence);
  build_body_csr(static_cast<std::size_t>(n), [&](auto emit) {
    for (std::size_t k = 0; k < model.loads.size(); ++k) emit(model.loads[k].body, static_cast<int>(k));
  }, compiled_->load_start, compiled_->load_index);
  compiled_->element_start.assign(static_cast<std::size_t>(n) + 1, 0);
  compiled_->driver_of_body.assign(static_cast<std::size_t>(n), -1);
  drive_memo_.assign(model.drivers.size(), DriveMemo{});
  for (std::size_t k = 0; k < model.drivers.size(); ++k)
    compiled_->driver_of_body[static_cast<std::size_t>(model.drivers[k].body)] = static_cast<int>(k);

  motor_effort_.setZero(nj);
  for (const auto& e : model.force_elements) add_force_element(e);
  compile_flexible();  // before the constraints: a flexible body's rigid joints join one cluster
  compile_constraints();
  // Every evaluation keeps rot_ where a flexible body's frame and nodes read it.
  compiled_->rotations_read = !model.loads.empty() || !compiled_->elements.empty() || !model.flexible.empty() ||
                              std::any_of(compiled_->joints.begin(), compiled_->joints.end(), [&](const CompiledJoint& j) { return !on_lanes(j); });
}

Eigen::VectorXd MultibodySystem::initial_state() const {
  Eigen::VectorXd y(dimension());
  for (Eigen::Index i = 0; i < layout_.bodies; ++i) {
    const Body& b = model().bodies[static_cast<std::size_t>(i)];
    y.segment<3>(layout_.position(i)) = vec(b.position);
    y.segment<4>(layout_.orientation(i)) = vec(b.orientation).normalized();
    y.segment<3>(layout_.velocity(i)) = vec(b.velocity);
    y.segment<3>(layout_.angular_velocity(i)) = vec(b.angular_velocity);
  }
  y.tail(layout_.extra).setZero();
  for (std::size_t f = 0; f < model().flexible.size(); ++f) {
    const FlexibleBody& fb = model().flexible[f];
    const Eigen::Index tail = layout_.tail(compiled_->flexible_tail[f]), ne = fb.data->modes();
    if (fb.initial_eta.size() == ne) y.segment(tail, ne) = fb.initial_eta;
    if (fb.initial_eta_rate.size() == ne) y.segment(tail + ne, ne) = fb.initial_eta_rate;
  }
  const double t0 = model().simulation.t_start;
  int given_joint = -1, worst_joint = -1;
  const double given = constraint_violation(t0, y, &given_joint);
  // A model is not changed behind its author's back: a joint that its bodies do not meet
  // is refused unless assembly was asked for.
  if (!(given <= SimulationSettings::assembly_tolerance) && !model().simulation.assemble && given_joint >= 0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", given);
    throw ModelError("rigid joint '" + model().joints[static_cast<std::size_t>(given_joint)].name +
                     "' is violated by " + buf + " (m or rad) in the initial positions: correct the bodies' positions "
                     "and orientations, or ask for assembly (mbsflow run --assemble, or \"assemble\": true in the "
                     "simulation block) to move the bodies onto the joints");
  }
  after_step(t0, y);
  // The projection assembles the rigid joints; if it cannot, no loop closes there.
  if (const double v = constraint_violation(t0, y, &worst_joint); !(v <= 1e-6)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", given);
    throw ModelError("rigid joint '" + model().joints[static_cast<std::size_t>(given_joint >= 0 ? given_joint : worst_joint)].name +
                     "' cannot be assembled with the others (violation " + buf +
                     " as given, and no projection removes it): the rigid joints over-constrain a loop in a way that "
                     "no position satisfies, or the initial positions are far from one that does");
  }
  return y;
}

[[gnu::always_inline]] inline BodyFrameView MultibodySystem::body_frame_at(int i) const {
  return {rot_[static_cast<std::size_t>(i)], pos_.col(i), vel_.col(i), omega_.col(i), quat_.col(i)};
}

// A driven body's kinematics replace what its state says.
void MultibodySystem::drive(const Driver& d, double t) {
  const Eigen::Index i = d.body;
  const Body& b = model().bodies[static_cast<std::size_t>(i)];
  DriveMemo& memo = drive_memo_[static_cast<std::size_t>(&d - model().drivers.data())];
  int slot = memo.find(t);
  if (slot < 0) {
    slot = memo.next;
    memo.next = (memo.next + 1) % DriveMemo::slots;
    memo.t[slot] = t;
    for (int k = 0; k < 3; ++k) {
      const FunctionValue f = evaluate(d.displacement[static_cast<std::size_t>(k)], t);
      memo.value[slot](k) = f.value;
      memo.rate[slot](k) = f.rate;
      memo.accel[slot](k) = f.accel;
    }
  }
  for (int k = 0; k < 3; ++k) {
    pos_(k, i) = b.position[static_cast<std::size_t>(k)] + d.velocity[static_cast<std::size_t>(k)] * t + memo.value[slot](k);
    vel_(k, i) = d.velocity[static_cast<std::size_t>(k)] + memo.rate[slot](k);
  }
  quat_.col(i) = vec(b.orientation).normalized();
  if (!rot_.empty()) rot_[static_cast<std::size_t>(i)] = rotation_matrix(quat_.col(i));
  omega_.col(i).setZero();
}

// The kinematics and joint wrenches of an evaluation (about 180 bytes a body, and 72 more
// where the rotation matrices are kept). Made at the first evaluation, not with the
// system: a system built for its layout, names and initial state only (a partitioned run's
// whole system, for its results) never holds them, and its copies (the results writer's)
// make their own when they first evaluate.
void MultibodySystem::make_workspace() {
  const Eigen::Index n = layout_.bodies;
  pos_ = Eigen::Matrix3Xd::Zero(3, n + 1);
  vel_ = Eigen::Matrix3Xd::Zero(3, n + 1);
  omega_ = Eigen::Matrix3Xd::Zero(3, n + 1);
  quat_ = Eigen::Matrix4Xd::Zero(4, n + 1);
  quat_(0, n) = 1.0;  // ground, at index n
}

// The plain copies here, the rotations on lanes after: the AVX kernels touch no Eigen
// double arithmetic (see lane_kernels.cpp), and a copy gains nothing from lanes.
void MultibodySystem::kinematics_in(const int* list, std::size_t n, const Eigen::VectorXd& y, bool all_rotations) {
  if (pos_.cols() == 0) make_workspace();
  const bool rotations = all_rotations || compiled_->rotations_read;
  if (rotations && rot_.empty()) rot_.assign(static_cast<std::size_t>(layout_.bodies) + 1, Eigen::Matrix3d::Identity());
  // The workspace's columns are laid out as the state's blocks, so each run of consecutive
  // bodies is three block copies.
  for_body_runs(list, n, [&](Eigen::Index first, Eigen::Index count) {
    std::copy_n(y.data() + layout_.orientation(first), 4 * count, quat_.col(first).data());
    std::copy_n(y.data() + layout_.position(first), 3 * count, pos_.col(first).data());
    std::copy_n(y.data() + layout_.velocity(first), 3 * count, vel_.col(first).data());
  });
  lane_groups_for_cpu<1>(
      list, n, [](int) { return 0; }, [](int) {}, [&](const int* k) { kinematics_on_lanes(k, y, rotations); },
      [&](const int* k) { kinematics_on_lanes_avx(k, y, rotations); });
}

void MultibodySystem::update_kinematics(double t, const Eigen::VectorXd& y) {
  time_ = t;
  kinematics_in(nullptr, static_cast<std::size_t>(layout_.bodies), y, true);
  for (const Driver& d : model().drivers) drive(d, t);
  follow_flexible(y);
}

void MultibodySystem::kinematics_for_rhs(double t, const Eigen::VectorXd& y) {
  time_ = t;
  kinematics_in(nullptr, static_cast<std::size_t>(layout_.bodies), y, false);
  for (const Driver& d : model().drivers) drive(d, t);
  follow_flexible(y);
}

void MultibodySystem::kinematics_of(double t, const Eigen::VectorXd& y, std::span<const int> bodies) {
  time_ = t;
  kinematics_in(bodies.data(), bodies.size(), y, false);
  // The last driver of a body wins, as in update_kinematics.
  for (int i : bodies)
    if (const int d = compiled_->driver_of_body[static_cast<std::size_t>(i)]; d >= 0) drive(model().drivers[static_cast<std::size_t>(d)], t);
  for (int f : flexible_framed(bodies)) follow_nodes_of(static_cast<std::size_t>(f), y);
}

[[gnu::always_inline]] inline void MultibodySystem::joint_force(std::size_t k) {
  const CompiledJoint& j = compiled_->joints[k];
  if (j.kinematic >= 0) {
    kinematic_joint_force(k);
    return;
  }
  compliant_joint_wrench<double>(law_of(j), tables_of(j), body_frame_at(j.a), body_frame_at(j.b), joint_out_.col(static_cast<Eigen::Index>(k)));
}

namespace {
template <class V>
std::size_t bytes_of(const V& v) {
  return v.capacity() * sizeof(typename V::value_type);
}
template <class M>
std::size_t matrix_bytes(const M& m) {
  return static_cast<std::size_t>(m.size()) * sizeof(typename M::Scalar);
}
}  // namespace

MultibodySystem::MemoryUse MultibodySystem::memory_use() const {
  const Compiled& c = *compiled_;
  MemoryUse m;
  m.compiled = bytes_of(c.body_law) + bytes_of(c.body_laws) + bytes_of(c.joints) + bytes_of(c.laws) +
               bytes_of(c.tables) + bytes_of(c.incidence_start) + bytes_of(c.incidence) + bytes_of(c.load_start) +
               bytes_of(c.load_index) + bytes_of(c.driver_of_body) + bytes_of(c.elements) + bytes_of(c.element_first) +
               bytes_of(c.element_start) + bytes_of(c.element_slot);
  m.workspace = bytes_of(drive_memo_) + bytes_of(element_out_) + bytes_of(rot_) + matrix_bytes(pos_) + matrix_bytes(vel_) +
                matrix_bytes(omega_) + matrix_bytes(quat_) + matrix_bytes(joint_out_) + bytes_of(jacobian_scratch_) +
                bytes_of(jacobian_slots_.outer) + bytes_of(jacobian_slots_.slots) +
                matrix_bytes(motor_effort_) + constraint_bytes();
  return m;
}

// Bushings without tables go several at a time (lane_kernels.cpp), grouped by their frame
// class; the other joints one by one.
bool MultibodySystem::on_lanes(const CompiledJoint& j) const { return j.kinematic < 0 && !law_of(j).spring && j.tables < 0; }

void MultibodySystem::joint_forces_in(const int* list, std::size_t n) {
  // Made here, not with the kinematics: a system that only computes energies (the results
  // writer's copy) never needs the joints' wrenches.
  if (const auto joints = static_cast<Eigen::Index>(compiled_->joints.size()); joint_out_.cols() != joints) joint_out_.setZero(9, joints);
  lane_groups_for_cpu<4>(
      list, n,
      [&](int k) {
        const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(k)];
        return on_lanes(j) ? 2 * law_of(j).frame1_identity + law_of(j).frame2_identity : -1;
      },
      [&](int k) { joint_force(static_cast<std::size_t>(k)); }, [&](const int* k) { bushings_on_lanes(k); },
      [&](const int* k) { bushings_on_lanes_avx(k); });
}

void MultibodySystem::compute_joint_forces() {
  joint_forces_in(nullptr, compiled_->joints.size());
  if (compiled_->elements.empty()) return;
  const Kinematics k = kinematics();
  for (std::size_t e = 0; e < compiled_->elements.size(); ++e) {
    const std::size_t first = compiled_->element_first[e], count = compiled_->element_first[e + 1] - first;
    compiled_->elements[e]->evaluate(time_, k, std::span<Wrench>(element_out_.data() + first, count));
  }
}

void MultibodySystem::joint_forces_of(std::span<const int> joints) {
  joint_forces_in(joints.data(), joints.size());
}

void MultibodySystem::add_force_element(std::shared_ptr<const ForceElement> element) {
  const std::vector<int> bodies = element->bodies();
  for (int b : bodies)
    if (b < 0 || b >= layout_.bodies) throw InputError("force element: body index " + std::to_string(b) + " out of range");
  if (compiled_.use_count() > 1) compiled_ = std::make_shared<Compiled>(*compiled_);  // shared with a copy
  if (compiled_->element_first.empty()) compiled_->element_first.push_back(0);
  const std::size_t first = element_out_.size();
  element_out_.resize(first + bodies.size());
  compiled_->element_first.push_back(element_out_.size());
  compiled_->elements.push_back(std::move(element));
  compiled_->rotations_read = true;
  // Rebuild the per-body slot lists, in element order.
  const int n = static_cast<int>(layout_.bodies);
  std::vector<int> body_of_slot(element_out_.size());
  for (std::size_t e = 0; e < compiled_->elements.size(); ++e) {
    const std::vector<int> b = compiled_->elements[e]->bodies();
    for (std::size_t i = 0; i < b.size(); ++i) body_of_slot[compiled_->element_first[e] + i] = b[i];
  }
  build_body_csr(static_cast<std::size_t>(n), [&](auto emit) {
    for (std::size_t slot = 0; slot < body_of_slot.size(); ++slot) emit(body_of_slot[slot], static_cast<int>(slot));
  }, compiled_->element_start, compiled_->element_slot);
}

void MultibodySystem::joint_wrenches(double t, const Eigen::VectorXd& y, Eigen::VectorXd& out) {
  if (clusters() > 0) {
    Eigen::VectorXd dydt(dimension());
    rhs(t, y, dydt);  // the rigid joints' multipliers too
  } else {
    update_kinematics(t, y);
    compute_joint_forces();
  }
  out.resize(6 * static_cast<Eigen::Index>(compiled_->joints.size()));
  for (std::size_t k = 0; k < compiled_->joints.size(); ++k) {
    const CompiledJoint& j = compiled_->joints[k];
    const auto col = joint_out_.col(static_cast<Eigen::Index>(k));
    const Eigen::Vector3d force = col.segment<3>(0);
    const Eigen::Vector3d arm = rot_[static_cast<std::size_t>(j.b)] * law_of(j).pb;  // centre of body2 to its point
    out.segment<3>(6 * static_cast<Eigen::Index>(k)) = force;
    out.segment<3>(6 * static_cast<Eigen::Index>(k) + 3) = col.segment<3>(6) - arm.cross(force);
  }
  add_reactions(out);
}

// Gravity, loads, joints and force elements on body i: force and torque (world, about
// the centre of mass), summed in the fixed order of the class comment.
void MultibodySystem::applied_wrench(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::Vector3d& force,
                                     Eigen::Vector3d& torque) const {
  // Summed in locals, stored once: sums through the references went to memory and back at
  // every term (they might alias what is summed).
  const auto bi = static_cast<std::size_t>(i);
  Eigen::Vector3d f = body_law(bi).mass * gravity_, m = Eigen::Vector3d::Zero();
  for (int p = compiled_->load_start[bi]; p < compiled_->load_start[bi + 1]; ++p) {
    const Load& l = model().loads[static_cast<std::size_t>(compiled_->load_index[static_cast<std::size_t>(p)])];
    if (follows_frame(bi))  // a flexible body's node: its velocities are the ones it follows with
      add_load<double>(l, evaluate(l.function, t).value, rot_[bi], Eigen::Vector3d(vel_.col(i)),
                       Eigen::Vector3d(rot_[bi].transpose() * omega_.col(i)), f, m);
    else
      add_load<double>(l, evaluate(l.function, t).value, rot_[bi], y.segment<3>(layout_.velocity(i)),
                       y.segment<3>(layout_.angular_velocity(i)), f, m);  // loads: rotations kept
  }
  for (int p = compiled_->incidence_start[bi]; p < compiled_->incidence_start[bi + 1]; ++p) {
    const int code = compiled_->incidence[static_cast<std::size_t>(p)];
    const auto col = joint_out_.col(code / 2);
    if (code & 1) {
      f += col.segment<3>(0);
      m += col.segment<3>(6);
    } else {
      f -= col.segment<3>(0);
      m += col.segment<3>(3);
    }
  }
  for (int p = compiled_->element_start[bi]; p < compiled_->element_start[bi + 1]; ++p) {
    const Wrench& w = element_out_[static_cast<std::size_t>(compiled_->element_slot[static_cast<std::size_t>(p)])];
    f += w.force;
    m += w.torque;
  }
  force = f;
  torque = m;
}

void MultibodySystem::write_derivative(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt,
                                       const Eigen::Vector3d& force, const Eigen::Vector3d& torque) const {
  const auto bi = static_cast<std::size_t>(i);
  const int drv = compiled_->driver_of_body[bi];
  if (drv >= 0) {
    const Driver& d = model().drivers[static_cast<std::size_t>(drv)];
    const DriveMemo& memo = drive_memo_[static_cast<std::size_t>(drv)];
    const int slot = memo.find(t);  // kept by this evaluation's kinematics
    for (int k = 0; k < 3; ++k) {
      dydt[layout_.position(i) + k] = vel_(k, i);
      dydt[layout_.velocity(i) + k] = slot >= 0 ? memo.accel[slot](k) : evaluate(d.displacement[static_cast<std::size_t>(k)], t).accel;
    }
    dydt.segment<4>(layout_.orientation(i)).setZero();
    dydt.segment<3>(layout_.angular_velocity(i)).setZero();
    return;
  }
  const Eigen::Vector3d w = y.segment<3>(layout_.angular_velocity(i));
  const Eigen::Vector4d q = y.segment<4>(layout_.orientation(i));
  dydt.segment<3>(layout_.position(i)) = y.segment<3>(layout_.velocity(i));
  const BodyLaw& law = body_law(bi);
  dydt.segment<3>(layout_.velocity(i)) = law.inv_mass * force;
  dydt.segment<3>(layout_.angular_velocity(i)) = angular_acceleration<double>(rot_[bi], w, torque, law.inertia, law.inv_inertia);
  dydt.segment<4>(layout_.orientation(i)) = quaternion_rate<double>(q, w);
}

[[gnu::always_inline]] inline void MultibodySystem::body_derivative(Eigen::Index i, double t, const Eigen::VectorXd& y,
                                                                      Eigen::VectorXd& dydt) const {
  Eigen::Vector3d force, torque;
  applied_wrench(i, t, y, force, torque);
  write_derivative(i, t, y, dydt, force, torque);
}

// Width free bodies: their applied wrenches in double, in the fixed order, then their rates
// on lanes. Every free body takes this way whatever the list it comes in (a driven or
// clustered one never does), so a partition's grouping leaves its numbers unchanged.
template <int Width>
void MultibodySystem::free_bodies_on_lanes(const int* k, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  double wrench[6 * Width];
  for (int l = 0; l < Width; ++l) {
    Eigen::Vector3d force, torque;
    applied_wrench(k[l], t, y, force, torque);
    Eigen::Map<Eigen::Vector3d>(wrench + 6 * l) = force;
    Eigen::Map<Eigen::Vector3d>(wrench + 6 * l + 3) = torque;
    dydt.segment<3>(layout_.position(k[l])) = y.segment<3>(layout_.velocity(k[l]));
  }
  if constexpr (Width == 4)
    rates_on_lanes_avx(k, wrench, y, dydt);
  else
    rates_on_lanes(k, wrench, y, dydt);
}

// The bodies list[0..n) (0..n-1 when null) but those of rigid clusters.
void MultibodySystem::derivatives_in(const int* list, std::size_t n, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  const bool any = clusters() > 0;
  lane_groups_for_cpu<1>(
      list, n,
      [&](int i) {
        if ((any && cluster_of(i) >= 0) || flexible_owned(i)) return -1;
        return compiled_->driver_of_body[static_cast<std::size_t>(i)] >= 0 ? -1 : 0;
      },
      [&](int i) {
        if ((!any || cluster_of(i) < 0) && !flexible_owned(i)) body_derivative(i, t, y, dydt);
      },
      [&](const int* k) { free_bodies_on_lanes<Lanes::width>(k, t, y, dydt); },
      [&](const int* k) { free_bodies_on_lanes<4>(k, t, y, dydt); });
}

void MultibodySystem::compute_derivatives(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  derivatives_in(nullptr, static_cast<std::size_t>(active_), t, y, dydt);
  for (int c = 0; c < clusters(); ++c) solve_cluster(c, t, y, dydt);
  flexible_derivatives(t, y, dydt);
}

// A listed body of a cluster brings in its whole cluster, a listed frame its flexible
// body's nodes and modes: the caller lists whole clusters and parts.
void MultibodySystem::derivatives_of(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt,
                                     std::span<const int> bodies) const {
  derivatives_in(bodies.data(), bodies.size(), t, y, dydt);
  for (int c : clusters_of(bodies)) solve_cluster(c, t, y, dydt);
  for (int f : flexible_framed(bodies)) flexible_derivative(static_cast<std::size_t>(f), t, y, dydt);
}

void MultibodySystem::rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
  kinematics_for_rhs(t, y);
  compute_joint_forces();
  compute_derivatives(t, y, dydt);
}

// A driven body's state put exactly on its prescribed motion.
void MultibodySystem::impose(const Driver& d, double t, Eigen::VectorXd& y) const {
  const Eigen::Index i = d.body;
  const Body& b = model().bodies[static_cast<std::size_t>(i)];
  for (int k = 0; k < 3; ++k) {
    const FunctionValue f = evaluate(d.displacement[static_cast<std::size_t>(k)], t);
    y[layout_.position(i) + k] = b.position[static_cast<std::size_t>(k)] + d.velocity[static_cast<std::size_t>(k)] * t + f.value;
    y[layout_.velocity(i) + k] = d.velocity[static_cast<std::size_t>(k)] + f.rate;
  }
  y.segment<4>(layout_.orientation(i)) = vec(b.orientation).normalized();
  y.segment<3>(layout_.angular_velocity(i)).setZero();
}

void MultibodySystem::after_step(double t, Eigen::VectorXd& y) const {
  for (Eigen::Index i = 0; i < layout_.bodies; ++i) y.segment<4>(layout_.orientation(i)).normalize();
  for (const Driver& d : model().drivers) impose(d, t, y);
  for (int c = 0; c < clusters(); ++c) project_cluster(c, t, y);
  place_flexible_nodes(y);
}

void MultibodySystem::after_step_of(double t, Eigen::VectorXd& y, std::span<const int> bodies) const {
  for (int i : bodies) {
    y.segment<4>(layout_.orientation(i)).normalize();
    if (const int d = compiled_->driver_of_body[static_cast<std::size_t>(i)]; d >= 0) impose(model().drivers[static_cast<std::size_t>(d)], t, y);
  }
  for (int c : clusters_of(bodies)) project_cluster(c, t, y);
  for (int f : flexible_framed(bodies)) place_nodes_of(static_cast<std::size_t>(f), y);
}

template <class Frame>
double MultibodySystem::elastic_energy(const CompiledJoint& j, const Frame& a, const Frame& b) const {
  const JointLaw& law = law_of(j);
  if (law.spring) {
    const Eigen::Vector3d delta = b.pos + b.rot * law.pb - a.pos - a.rot * law.pa;
    const double e = delta.norm() - law.rest_length;
    return 0.5 * law.kt[0] * e * e;
  }
  const DeflectionT<double> def = bushing_deflection<double>(law, a, b);
  const Eigen::Vector3d& theta = def.rotation.theta;
  double e = -law.preload_force.dot(def.d) - law.preload_torque.dot(theta);
  for (int axis = 0; axis < 6; ++axis) {
    const double x = axis < 3 ? def.d[axis] : theta[axis - 3];
    const double k = axis < 3 ? law.kt[axis] : law.kr[axis - 3];
    const ForceTable* table = j.tables >= 0 ? &compiled_->tables[static_cast<std::size_t>(j.tables)][static_cast<std::size_t>(axis)] : nullptr;
    e += (table && !table->empty()) ? table_energy(*table, x) : 0.5 * k * x * x;
  }
  return e;
}

// A body's frame from its state alone (ground at index n), bit for bit as an evaluation's
// kinematics hold it: the rotation matrix is the same arithmetic as on the lanes.
BodyFrameT<double> MultibodySystem::frame_from_state(int i, const Eigen::VectorXd& y) const {
  if (i == layout_.bodies) {
    BodyFrameT<double> ground_frame;
    ground_frame.rot.setIdentity();
    ground_frame.pos.setZero();
    ground_frame.vel.setZero();
    ground_frame.omega.setZero();
    ground_frame.quat = Eigen::Vector4d(1.0, 0.0, 0.0, 0.0);
    return ground_frame;
  }
  return body_frame<double>(y.segment<3>(layout_.position(i)), y.segment<4>(layout_.orientation(i)),
                            y.segment<3>(layout_.velocity(i)), y.segment<3>(layout_.angular_velocity(i)));
}

Energy MultibodySystem::energy(double t, const Eigen::VectorXd& y) {
  // Without drivers, force elements and kinematic joints the energies need only the state,
  // and no workspace is made: the results writer's copy of a million-body system, which
  // evaluates nothing else, would otherwise hold 176 MB of kinematics.
  const bool from_state = model().drivers.empty() && compiled_->elements.empty() && constraints_->geometry.empty() &&
                          model().flexible.empty();
  if (!from_state) update_kinematics(t, y);
  Energy e;
  for (Eigen::Index i = 0; i < layout_.bodies; ++i) {
    const auto bi = static_cast<std::size_t>(i);
    if (flexible_owned(i)) continue;  // flexible_energy below
    const double m = model().bodies[bi].mass;
    const Eigen::Vector3d w = y.segment<3>(layout_.angular_velocity(i));
    // The kinematics copy a free body's position and velocity from y; a driven body's follow its driver.
    const bool driven = compiled_->driver_of_body[bi] >= 0;
    const Eigen::Vector3d v = driven ? Eigen::Vector3d(vel_.col(i)) : Eigen::Vector3d(y.segment<3>(layout_.velocity(i)));
    const Eigen::Vector3d r = driven ? Eigen::Vector3d(pos_.col(i)) : Eigen::Vector3d(y.segment<3>(layout_.position(i)));
    e.kinetic += 0.5 * m * v.squaredNorm() + 0.5 * w.dot(body_law(bi).inertia * w);
    e.gravity -= m * gravity_.dot(r);
  }
  for (const CompiledJoint& j : compiled_->joints)
    e.elastic += from_state        ? elastic_energy(j, frame_from_state(j.a, y), frame_from_state(j.b, y))
                 : j.kinematic >= 0 ? kinematic_energy(j)
                                    : elastic_energy(j, body_frame_at(j.a), body_frame_at(j.b));
  if (from_state) return e;
  flexible_energy(y, e);
  const Kinematics k = kinematics();
  for (const auto& element : compiled_->elements) e.elastic += element->energy(t, k);
  return e;
}

}  // namespace mbsflow
