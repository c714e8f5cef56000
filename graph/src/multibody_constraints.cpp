// The kinematic joints of MultibodySystem: compliant ones as forces along their
// constraint rows, rigid ones solved per cluster, and the projection after each step.
#include <algorithm>
#include <array>
#include <cmath>

#include "constraint_rows.hpp"
#include "kinematic_joint_wrench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "multibody_constraints.hpp"
#include "rigid_cluster.hpp"
#include "rotation.hpp"

namespace mbsflow {
std::size_t MultibodySystem::constraint_bytes() const {
  const Constraints& k = *constraints_;
  std::size_t lambda = 0;
  for (const Eigen::VectorXd& l : k.lambda) lambda += static_cast<std::size_t>(l.size()) * sizeof(double);
  return sizeof(Constraints) + k.geometry.capacity() * sizeof(JointGeometry) + k.clusters.capacity() * sizeof(RigidCluster) +
         k.cluster_of_body.capacity() * sizeof(int) + k.lambda.capacity() * sizeof(Eigen::VectorXd) + lambda + k.marked.capacity() +
         k.wrench.capacity() * sizeof(Vector6d) + k.motion.capacity() * sizeof(BodyMotion) +
         (k.force.capacity() + k.torque.capacity()) * sizeof(Eigen::Vector3d) + k.flexible_of_cluster.capacity() * sizeof(int) +
         k.flexible.capacity() * sizeof(FlexibleSlots);
}

void MultibodySystem::compile_constraints() {
  constraints_ = detail::DeepPtr<Constraints>(
      new Constraints, [](const Constraints& c) { return new Constraints(c); }, [](Constraints* c) { delete c; });
  Constraints& k = *constraints_;
  const int n = static_cast<int>(layout_.bodies);
  std::vector<char> touched(static_cast<std::size_t>(n), 0);
  for (std::size_t j = 0; j < model().joints.size(); ++j) {
    const Joint& joint = model().joints[j];
    if (!is_kinematic(joint.type)) continue;
    CompiledJoint& c = compiled_->joints[j];
    c.kinematic = static_cast<int>(k.geometry.size());
    c.rigid = joint.rigid;
    c.applies_force = !joint.rigid || joint.limits->active || joint.motor->kind == JointMotor::Kind::effort;
    k.geometry.push_back(joint_geometry(joint));
    if (!joint.rigid) continue;
    touched[static_cast<std::size_t>(joint.body2)] = 1;
    if (joint.body1 != ground) touched[static_cast<std::size_t>(joint.body1)] = 1;
  }
  // The partitioners' rigid pieces, less the bodies without a rigid joint: clusters in
  // the order of their first body, bodies ascending.
  std::vector<int> piece = rigid_pieces(model());
  join_flexible_pieces(touched, piece);
  k.cluster_of_body.assign(static_cast<std::size_t>(n), -1);
  std::vector<int> cluster_of_piece(static_cast<std::size_t>(n), -1);
  std::vector<std::vector<int>> bodies;
  for (int i = 0; i < n; ++i) {
    if (!touched[static_cast<std::size_t>(i)]) continue;
    int& c = cluster_of_piece[static_cast<std::size_t>(piece[static_cast<std::size_t>(i)])];
    if (c < 0) {
      c = static_cast<int>(bodies.size());
      bodies.emplace_back();
    }
    bodies[static_cast<std::size_t>(c)].push_back(i);
    k.cluster_of_body[static_cast<std::size_t>(i)] = c;
  }
  std::vector<std::vector<ClusterJoint>> joints(bodies.size());
  std::vector<int> rows(bodies.size(), 0);
  for (std::size_t j = 0; j < model().joints.size(); ++j) {
    const Joint& joint = model().joints[j];
    if (!is_kinematic(joint.type) || !joint.rigid) continue;
    const auto c = static_cast<std::size_t>(k.cluster_of_body[static_cast<std::size_t>(joint.body2)]);
    auto slot = [&](int body) {
      if (body == ground) return -1;
      const auto& list = bodies[c];
      return static_cast<int>(std::lower_bound(list.begin(), list.end(), body) - list.begin());
    };
    ClusterJoint cj{static_cast<int>(j), slot(joint.body1), slot(joint.body2), rows[c],
                    constraint_rows(k.geometry[static_cast<std::size_t>(compiled_->joints[j].kinematic)])};
    rows[c] += cj.rows;
    joints[c].push_back(cj);
  }
  k.clusters.reserve(bodies.size());  // no copies of clusters not yet factored
  for (std::size_t c = 0; c < bodies.size(); ++c) {
    if (bodies[c].back() >= active_)
      throw InputError("rigid joint '" + model().joints[static_cast<std::size_t>(joints[c].front().joint)].name +
                       "' joins bodies of different submodels: a cut may only pass through compliant joints, bushings and springs");
    k.clusters.emplace_back(std::move(bodies[c]), std::move(joints[c]));
    k.lambda.emplace_back(Eigen::VectorXd::Zero(k.clusters.back().row_count()));
  }
  k.marked.assign(k.clusters.size(), 0);
  if (model().flexible.empty()) return;
  k.flexible_of_cluster.assign(k.clusters.size(), -1);
  for (std::size_t c = 0; c < k.clusters.size(); ++c)
    if (FlexibleSlots fs = flexible_slots(k.clusters[c].bodies()); !fs.flexible.empty()) {
      k.flexible_of_cluster[c] = static_cast<int>(k.flexible.size());
      k.flexible.push_back(std::move(fs));
    }
}

BodyMotion MultibodySystem::motion_at(int i) const {
  return {pos_.col(i), rot_[static_cast<std::size_t>(i)], vel_.col(i), omega_.col(i)};
}

std::vector<int> MultibodySystem::clusters_of(std::span<const int> bodies) const {
  std::vector<int> out;
  if (clusters() == 0) return out;
  for (int i : bodies)
    if (const int c = cluster_of(i); c >= 0) out.push_back(c);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

int MultibodySystem::clusters() const { return static_cast<int>(constraints_->clusters.size()); }
const std::vector<int>& MultibodySystem::cluster_bodies(int c) const {
  return constraints_->clusters[static_cast<std::size_t>(c)].bodies();
}
int MultibodySystem::cluster_of(int body) const { return constraints_->cluster_of_body[static_cast<std::size_t>(body)]; }

void MultibodySystem::kinematic_joint_force(std::size_t k) {
  const CompiledJoint& j = compiled_->joints[k];
  auto out = joint_out_.col(static_cast<Eigen::Index>(k));
  out.setZero();
  if (!j.applies_force) return;
  kinematic_joint_wrench<double>(law_of(j), j.rigid, geometry_of(j), motion_at(j.a), motion_at(j.b), time_, out,
                                 &motor_effort_[static_cast<Eigen::Index>(k)]);
}

const JointGeometry& MultibodySystem::geometry_of(const CompiledJoint& j) const {
  return constraints_->geometry[static_cast<std::size_t>(j.kinematic)];
}

double MultibodySystem::kinematic_energy(const CompiledJoint& j) const {
  if (!j.applies_force) return 0.0;
  const JointGeometry& g = constraints_->geometry[static_cast<std::size_t>(j.kinematic)];
  const BodyMotion a = motion_at(j.a);
  const BodyMotion b = motion_at(j.b);
  double e = 0.0;
  if (!j.rigid) {
    std::array<ConstraintRow, max_joint_rows> rows;
    const int n = constraint_rows(g);
    evaluate_constraint(g, a, b, time_, rows.data());
    for (int r = 0; r < n; ++r) {
      const ConstraintRow& row = rows[static_cast<std::size_t>(r)];
      e += 0.5 * on_axis(row, law_of(j).kt, law_of(j).kr) * row.phi * row.phi;
    }
  }
  if (g.limits.active) {
    const double s = joint_coordinate(g, a, b).phi;
    const double over = s < g.limits.lower ? g.limits.lower - s : s > g.limits.upper ? s - g.limits.upper : 0.0;
    e += 0.5 * g.limits.stiffness * over * over;
  }
  return e;
}

// The applied wrenches of cluster c's bodies (k.force, k.torque), their inverse masses
// (into the cluster) and their accelerations under those alone (k.wrench); a flexible
// body's slots are left to solve_flexible_cluster.
void MultibodySystem::unconstrained_cluster(int c, double t, const Eigen::VectorXd& y) const {
  Constraints& k = *constraints_;
  RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const std::vector<int>& bodies = rc.bodies();
  const std::size_t nb = bodies.size();
  k.force.resize(nb);
  k.torque.resize(nb);
  std::vector<Vector6d>& accel = k.wrench;
  accel.resize(nb);
  for (std::size_t s = 0; s < nb; ++s) {
    const int i = bodies[s];
    const auto bi = static_cast<std::size_t>(i);
    if (flexible_owned(i)) continue;
    applied_wrench(i, t, y, k.force[s], k.torque[s]);
    if (const int d = compiled_->driver_of_body[bi]; d >= 0) {
      rc.inv_mass[s] = 0.0;
      rc.inv_inertia[s].setZero();
      const Driver& drv = model().drivers[static_cast<std::size_t>(d)];
      for (int a = 0; a < 3; ++a) accel[s][a] = evaluate(drv.displacement[static_cast<std::size_t>(a)], t).accel;
      accel[s].tail<3>().setZero();
      continue;
    }
    const Eigen::Matrix3d& r = rot_[bi];
    const Eigen::Vector3d w = y.segment<3>(layout_.angular_velocity(i));
    const BodyLaw& law = body_law(bi);
    rc.inv_mass[s] = law.inv_mass;
    rc.inv_inertia[s] = r * law.inv_inertia * r.transpose();
    accel[s].head<3>() = law.inv_mass * k.force[s];
    accel[s].tail<3>() = r * (law.inv_inertia * (r.transpose() * k.torque[s] - w.cross(law.inertia * w)));
  }
}

// Applied wrenches, rows, S, multipliers, and the derivatives of the cluster's bodies.
void MultibodySystem::solve_cluster(int c, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  Constraints& k = *constraints_;
  if (k.flexible_slots_of(c)) return solve_flexible_cluster(c, t, y, dydt);
  unconstrained_cluster(c, t, y);
  RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const std::vector<int>& bodies = rc.bodies();
  const std::size_t nb = bodies.size();
  const std::vector<Vector6d>& accel = k.wrench;  // unconstrained accelerations first
  Eigen::VectorXd& lambda = k.lambda[static_cast<std::size_t>(c)];
  for (const ClusterJoint& cj : rc.joints()) {
    const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
    const BodyMotion a = motion_at(j.a);
    const BodyMotion b = motion_at(j.b);
    ConstraintRow* rows = rc.rows.data() + cj.first_row;
    evaluate_constraint(k.geometry[static_cast<std::size_t>(j.kinematic)], a, b, t, rows);
    for (int r = 0; r < cj.rows; ++r) {
      double ja = rows[r].bias;
      if (cj.a >= 0) ja += rows[r].j.head<6>().dot(accel[static_cast<std::size_t>(cj.a)]);
      if (cj.b >= 0) ja += rows[r].j.tail<6>().dot(accel[static_cast<std::size_t>(cj.b)]);
      lambda[cj.first_row + r] = -ja;
    }
  }
  rc.factor();
  rc.solve(lambda);
  rc.wrenches(lambda, k.wrench);
  for (std::size_t s = 0; s < nb; ++s)
    write_derivative(bodies[s], t, y, dydt, k.force[s] + k.wrench[s].head<3>(), k.torque[s] + k.wrench[s].tail<3>());
}

BodyMotion state_motion(const StateLayout& l, const Eigen::VectorXd& y, Eigen::Index i) {
  BodyMotion m;
  if (i >= l.bodies) return m;  // ground
  m.r = y.segment<3>(l.position(i));
  m.R = rotation_matrix(y.segment<4>(l.orientation(i)));
  m.v = y.segment<3>(l.velocity(i));
  m.w = m.R * y.segment<3>(l.angular_velocity(i));
  return m;
}

// Newton iterations on the positions (mass-weighted, so the smallest kinetic-energy-like
// change), then one projection of the velocities: the state after a step lies on the
// constraints to within projection_tolerance, whatever the method.
void MultibodySystem::project_cluster(int c, double t, Eigen::VectorXd& y) const {
  Constraints& k = *constraints_;
  if (k.flexible_slots_of(c)) return project_flexible_cluster(c, t, y);
  RigidCluster& rc = k.clusters[static_cast<std::size_t>(c)];
  const std::vector<int>& bodies = rc.bodies();
  const std::size_t nb = bodies.size();
  // Rows and the inverse masses (for S) at y; the largest position violation.
  auto evaluate_rows = [&] {
    double worst = 0.0;
    for (const ClusterJoint& cj : rc.joints()) {
      const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
      ConstraintRow* rows = rc.rows.data() + cj.first_row;
      evaluate_constraint(k.geometry[static_cast<std::size_t>(j.kinematic)], state_motion(layout_, y, j.a),
                          state_motion(layout_, y, j.b), t, rows);
      for (int r = 0; r < cj.rows; ++r)
        if (rows[r].holonomic) worst = std::max(worst, std::abs(rows[r].phi));
    }
    for (std::size_t s = 0; s < nb; ++s) {
      const int i = bodies[s];
      const auto bi = static_cast<std::size_t>(i);
      const bool driven = compiled_->driver_of_body[bi] >= 0;
      const Eigen::Matrix3d r = rotation_matrix(y.segment<4>(layout_.orientation(i)));
      rc.inv_mass[s] = driven ? 0.0 : body_law(bi).inv_mass;
      rc.inv_inertia[s] = driven ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(r * body_law(bi).inv_inertia * r.transpose());
    }
    return worst;
  };
  // Newton's method with S factored afresh at every iterate. A factorisation kept from
  // the first iterate (simplified Newton) diverged on the A05 governor after implicit
  // steps of tolerance 1e-3: its rods and shaft turn about their own axes with inertias
  // of 5e-6 kg m^2, so S = J M^-1 J^T changes by far more than J does, and the stale S
  // turned a violation of 3e-6 m into 0.18 m, then the velocity projection a spin of
  // 5e5 rad/s. The velocities below are projected with S factored at the final positions.
  Eigen::VectorXd mu(rc.row_count());
  std::vector<Vector6d>& delta = k.wrench;
  for (int iteration = 0; iteration < projection_iterations; ++iteration) {
    if (evaluate_rows() <= projection_tolerance) break;
    for (int r = 0; r < rc.row_count(); ++r) mu[r] = rc.rows[static_cast<std::size_t>(r)].holonomic ? -rc.rows[static_cast<std::size_t>(r)].phi : 0.0;
    rc.factor();
    rc.solve(mu);
    rc.motion(mu, delta);
    for (std::size_t s = 0; s < nb; ++s) {
      const Eigen::Index i = bodies[s];
      y.segment<3>(layout_.position(i)) += delta[s].head<3>();
      const Eigen::Vector4d q = quat_multiply(quat_exp(delta[s].tail<3>()), y.segment<4>(layout_.orientation(i)));
      y.segment<4>(layout_.orientation(i)) = q.normalized();
    }
    if (iteration == projection_iterations - 1) evaluate_rows();
  }
  // Velocities: remove the part that violates phi' = 0.
  velocity_violations(rc, y, mu);
  rc.factor();
  rc.solve(mu);
  rc.motion(mu, delta);
  for (std::size_t s = 0; s < nb; ++s) {
    const Eigen::Index i = bodies[s];
    const Eigen::Matrix3d r = rotation_matrix(y.segment<4>(layout_.orientation(i)));
    y.segment<3>(layout_.velocity(i)) += delta[s].head<3>();
    y.segment<3>(layout_.angular_velocity(i)) += r.transpose() * delta[s].tail<3>();
  }
}

void MultibodySystem::velocity_violations(const RigidCluster& rc, const Eigen::VectorXd& y, Eigen::VectorXd& mu) const {
  for (const ClusterJoint& cj : rc.joints()) {
    const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
    const RowJacobian v = row_velocities<double>(state_motion(layout_, y, j.a), state_motion(layout_, y, j.b));
    for (int r = 0; r < cj.rows; ++r) {
      const ConstraintRow& row = rc.rows[static_cast<std::size_t>(cj.first_row + r)];
      mu[cj.first_row + r] = -(row.j.dot(v) + row.rate);
    }
  }
}

void MultibodySystem::for_each_rigid_row(double t, const Eigen::VectorXd& y,
                                         const std::function<void(const CompiledJoint&, std::size_t, const ConstraintRow&)>& row) const {
  std::array<ConstraintRow, max_joint_rows> rows;
  for (std::size_t k = 0; k < compiled_->joints.size(); ++k) {
    const CompiledJoint& j = compiled_->joints[k];
    if (j.kinematic < 0 || !j.rigid) continue;
    const JointGeometry& g = constraints_->geometry[static_cast<std::size_t>(j.kinematic)];
    evaluate_constraint(g, state_motion(layout_, y, j.a), state_motion(layout_, y, j.b), t, rows.data());
    for (int r = 0; r < constraint_rows(g); ++r) row(j, k, rows[static_cast<std::size_t>(r)]);
  }
}

double MultibodySystem::constraint_violation(double t, const Eigen::VectorXd& y, int* joint) const {
  double worst = 0.0;
  for_each_rigid_row(t, y, [&](const CompiledJoint&, std::size_t k, const ConstraintRow& row) {
    if (row.holonomic && std::abs(row.phi) > worst) {
      worst = std::abs(row.phi);
      if (joint) *joint = static_cast<int>(k);
    }
  });
  return worst;
}

Eigen::VectorXd MultibodySystem::constraint_values(double t, const Eigen::VectorXd& y) const {
  Eigen::VectorXd placed = y;
  place_flexible_nodes(placed);
  std::vector<double> values;
  for_each_rigid_row(t, placed, [&](const CompiledJoint&, std::size_t, const ConstraintRow& row) { values.push_back(row.holonomic ? row.phi : 0.0); });
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

Eigen::SparseMatrix<double> MultibodySystem::constraint_jacobian(double t, const Eigen::VectorXd& y,
                                                                std::vector<int>* joint_of_row) const {
  std::vector<Eigen::Triplet<double>> entries;
  const int n = static_cast<int>(layout_.bodies);
  int row = 0;
  if (joint_of_row) joint_of_row->clear();
  for_each_rigid_row(t, y, [&](const CompiledJoint& j, std::size_t k, const ConstraintRow& c) {
    for (int side = 0; side < 2; ++side) {
      const int body = side == 0 ? j.a : j.b;
      if (body >= n) continue;  // ground
      for (int e = 0; e < 6; ++e)
        if (const double v = c.j[6 * side + e]; v != 0.0) entries.emplace_back(row, 6 * body + e, v);
    }
    if (joint_of_row) joint_of_row->push_back(static_cast<int>(k));
    ++row;
  });
  Eigen::SparseMatrix<double> out(row, 6 * n);
  out.setFromTriplets(entries.begin(), entries.end());
  return out;
}

void MultibodySystem::add_reactions(Eigen::VectorXd& out) {
  Constraints& k = *constraints_;
  for (std::size_t c = 0; c < k.clusters.size(); ++c) {
    const RigidCluster& rc = k.clusters[c];
    for (const ClusterJoint& cj : rc.joints()) {
      Eigen::Matrix<double, 9, 1> w = Eigen::Matrix<double, 9, 1>::Zero();
      for (int r = 0; r < cj.rows; ++r)
        add_row_wrench(rc.rows[static_cast<std::size_t>(cj.first_row + r)], k.lambda[c][cj.first_row + r], w);
      const CompiledJoint& j = compiled_->joints[static_cast<std::size_t>(cj.joint)];
      // A position or velocity motor is the joint's last row: its multiplier is the effort.
      const JointMotor::Kind motor = k.geometry[static_cast<std::size_t>(j.kinematic)].motor.kind;
      if (motor != JointMotor::Kind::none && motor != JointMotor::Kind::effort)
        motor_effort_[cj.joint] = k.lambda[c][cj.first_row + cj.rows - 1];
      const Eigen::Vector3d arm = rot_[static_cast<std::size_t>(j.b)] * law_of(j).pb;
      const Eigen::Index at = 6 * static_cast<Eigen::Index>(cj.joint);
      out.segment<3>(at) += w.segment<3>(0);
      out.segment<3>(at + 3) += w.segment<3>(6) - arm.cross(Eigen::Vector3d(w.segment<3>(0)));
    }
  }
}

}  // namespace mbsflow
