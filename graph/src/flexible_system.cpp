// The flexible bodies' part of MultibodySystem (flexible_body.hpp): their node bodies'
// motion from the frame and the modes, their rates, and their state tail.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "flexible_dynamics.hpp"
#include "flexible_state.hpp"
#include "force_laws.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "rotation.hpp"

namespace mbsflow {
namespace {

using flexible_dynamics::node_world;
using NodeWorld = flexible_dynamics::NodeWorldT<double>;

NodeWorld node_world(const FlexibleAt& f, int k, const Eigen::Vector3d& pos, const Eigen::Vector3d& vel, const Eigen::Vector4d& quat,
                     const Eigen::Matrix3d& r) {
  return node_world<double>(f.d, k, f.eta, f.eta_rate, pos, vel, quat, r, f.w);
}

}  // namespace

void MultibodySystem::compile_flexible() {
  const Model& m = *model_;
  if (m.flexible.empty()) return;
  const auto n = static_cast<std::size_t>(layout_.bodies);
  compiled_->flexible_of_body.assign(n, -1);
  // The node bodies' masses serve the stable-step estimates only: their motion is the
  // frame's and the modes', and gravity acts on the part through the frame.
  const int massless = static_cast<int>(compiled_->body_laws.size());
  BodyLaw none;
  none.inertia.setZero();
  none.inv_inertia.setZero();
  compiled_->body_laws.push_back(none);
  for (std::size_t f = 0; f < m.flexible.size(); ++f) {
    const FlexibleBody& fb = m.flexible[f];
    const auto bad = [&](const std::string& what) { throw InputError("flexible body '" + fb.name + "': " + what); };
    if (!fb.data) bad("no reduced part");
    const int ne = fb.data->modes();
    if (fb.nodes.size() != fb.data->node_id.size()) bad("a body per interface node");
    if (fb.damping.size() != ne) bad("a damping coefficient per mode");
    std::vector<int> owned{fb.frame};
    owned.insert(owned.end(), fb.nodes.begin(), fb.nodes.end());
    for (int b : owned) {
      if (b < 0 || static_cast<std::size_t>(b) >= n || compiled_->flexible_of_body[static_cast<std::size_t>(b)] >= 0)
        bad("its bodies must be distinct bodies of the model");
      if (b >= active_) bad("its bodies must be integrated here (a submodel holds a flexible body whole)");
      compiled_->flexible_of_body[static_cast<std::size_t>(b)] = static_cast<int>(f);
      if (compiled_->driver_of_body[static_cast<std::size_t>(b)] >= 0)
        bad("body '" + m.bodies[static_cast<std::size_t>(b)].name + "' cannot be driven (drive a body and join it to the part by a fixed joint)");
    }
    for (int b : fb.nodes) compiled_->body_law[static_cast<std::size_t>(b)] = massless;
  }
  const std::vector<Eigen::Index> tail = flexible_tail_offsets(m.flexible);
  compiled_->flexible_tail.assign(tail.begin(), tail.end() - 1);
  layout_.extra = tail.back();
}

void MultibodySystem::follow_flexible(const Eigen::VectorXd& y) {
  for (std::size_t f = 0; f < model().flexible.size(); ++f) follow_nodes_of(f, y);
}

void MultibodySystem::follow_nodes_of(std::size_t f, const Eigen::VectorXd& y) {
  const FlexibleBody& fb = model().flexible[f];
  const FlexibleAt at = flexible_at(fb, layout_, compiled_->flexible_tail[f], y);
  const int i = at.frame;
  const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(i)];
  for (std::size_t k = 0; k < fb.nodes.size(); ++k) {
    const int b = fb.nodes[k];
    const NodeWorld n = node_world(at, static_cast<int>(k), pos_.col(i), vel_.col(i), quat_.col(i), r);
    pos_.col(b) = n.position;
    vel_.col(b) = n.velocity;
    omega_.col(b) = n.omega;
    quat_.col(b) = n.quat;
    rot_[static_cast<std::size_t>(b)] = rotation_matrix(n.quat);
  }
}

// Generalised forces (flexible_dynamics::generalised_force) from the frame's and the
// nodes' applied wrenches.
Eigen::VectorXd MultibodySystem::flexible_force(std::size_t f, const FlexibleAt& at, double t, const Eigen::VectorXd& y) const {
  const FlexibleBody& fb = model().flexible[f];
  return flexible_dynamics::generalised_force<double>(
      *fb.data, rot_[static_cast<std::size_t>(fb.frame)], gravity_, at.eta, [&](int k, Eigen::Vector3d& force, Eigen::Vector3d& torque) {
        applied_wrench(k < 0 ? fb.frame : fb.nodes[static_cast<std::size_t>(k)], t, y, force, torque);
      });
}

Eigen::VectorXd MultibodySystem::free_flexible_accelerations(std::size_t f, const FlexibleAt& at, const Eigen::VectorXd& y,
                                                             const Eigen::VectorXd& q) const {
  const FlexibleBody& fb = model().flexible[f];
  const Eigen::Vector3d v_b = rot_[static_cast<std::size_t>(at.frame)].transpose() * y.segment<3>(layout_.velocity(at.frame));
  return flexible_accelerations(fb, v_b, at.w, at.eta, at.eta_rate, q);
}

void MultibodySystem::write_flexible_rates(std::size_t f, const FlexibleAt& at, const Eigen::VectorXd& xi_rate,
                                           const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  const FlexibleBody& fb = model().flexible[f];
  const int ne = at.ne, i = at.frame;
  const Eigen::Vector3d& w = at.w;
  const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(i)];
  const Eigen::Vector3d v = y.segment<3>(layout_.velocity(i)), v_b = r.transpose() * v;
  const Eigen::Vector4d quat = y.segment<4>(layout_.orientation(i));
  dydt.segment<3>(layout_.position(i)) = v;
  dydt.segment<4>(layout_.orientation(i)) = quaternion_rate<double>(quat, w);
  dydt.segment<3>(layout_.velocity(i)) = r * (xi_rate.head<3>() + w.cross(v_b));
  dydt.segment<3>(layout_.angular_velocity(i)) = xi_rate.segment<3>(3);
  dydt.segment(at.tail, ne) = at.eta_rate;
  dydt.segment(at.tail + ne, ne) = xi_rate.tail(ne);
  // The nodes' states follow the frame (after_step puts them there); between steps they
  // move with its kinematics, for the dense output.
  for (int b : fb.nodes) {
    dydt.segment<3>(layout_.position(b)) = vel_.col(b);
    dydt.segment<4>(layout_.orientation(b)) = quaternion_rate<double>(
        Eigen::Vector4d(quat_.col(b)), Eigen::Vector3d(rot_[static_cast<std::size_t>(b)].transpose() * omega_.col(b)));
    dydt.segment<3>(layout_.velocity(b)).setZero();
    dydt.segment<3>(layout_.angular_velocity(b)).setZero();
  }
}

// A flexible body with a rigid joint at it is solved with its cluster (solve_cluster).
void MultibodySystem::flexible_derivative(std::size_t f, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  if (clusters() > 0 && cluster_of(model().flexible[f].frame) >= 0) return;
  const FlexibleAt at = flexible_at(model().flexible[f], layout_, compiled_->flexible_tail[f], y);
  write_flexible_rates(f, at, free_flexible_accelerations(f, at, y, flexible_force(f, at, t, y)), y, dydt);
}

void MultibodySystem::flexible_derivatives(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const {
  for (std::size_t f = 0; f < model().flexible.size(); ++f) flexible_derivative(f, t, y, dydt);
}

std::vector<int> MultibodySystem::flexible_framed(std::span<const int> bodies) const {
  std::vector<int> out;
  if (compiled_->flexible_of_body.empty()) return out;
  for (int i : bodies)
    if (const int f = compiled_->flexible_of_body[static_cast<std::size_t>(i)]; f >= 0 && model().flexible[static_cast<std::size_t>(f)].frame == i)
      out.push_back(f);
  std::sort(out.begin(), out.end());
  return out;
}

void MultibodySystem::place_nodes_of(std::size_t f, Eigen::VectorXd& y) const {
  const FlexibleAt at = flexible_at(model().flexible[f], layout_, compiled_->flexible_tail[f], y);
  const int i = at.frame;
  const Eigen::Vector4d qf = y.segment<4>(layout_.orientation(i));
  const Eigen::Matrix3d r = rotation_matrix(qf);
  for (std::size_t k = 0; k < model().flexible[f].nodes.size(); ++k) {
    const int b = model().flexible[f].nodes[k];
    const NodeWorld n = node_world(at, static_cast<int>(k), y.segment<3>(layout_.position(i)), y.segment<3>(layout_.velocity(i)), qf, r);
    y.segment<3>(layout_.position(b)) = n.position;
    y.segment<3>(layout_.velocity(b)) = n.velocity;
    y.segment<4>(layout_.orientation(b)) = n.quat;
    y.segment<3>(layout_.angular_velocity(b)) = rotation_matrix(n.quat).transpose() * n.omega;
  }
}

void MultibodySystem::place_flexible_nodes(Eigen::VectorXd& y) const {
  for (std::size_t f = 0; f < model().flexible.size(); ++f) place_nodes_of(f, y);
}

void MultibodySystem::flexible_energy(const Eigen::VectorXd& y, Energy& e) const {
  const Model& m = model();
  for (std::size_t f = 0; f < m.flexible.size(); ++f) {
    const FlexibleAt at = flexible_at(m.flexible[f], layout_, compiled_->flexible_tail[f], y);
    const int i = at.frame;
    const Eigen::Matrix3d& r = rot_[static_cast<std::size_t>(i)];  // energy() updated the kinematics
    const Eigen::Vector3d v_b = r.transpose() * y.segment<3>(layout_.velocity(i));
    e.kinetic += flexible_kinetic_energy(at.d, v_b, at.w, at.eta, at.eta_rate);
    e.gravity -= gravity_.dot(at.d.mass * y.segment<3>(layout_.position(i)) + r * (at.d.mass0.block(0, 6, 3, at.ne) * at.eta));
    e.elastic += flexible_strain_energy(at.d, at.eta);
  }
}

}  // namespace mbsflow
