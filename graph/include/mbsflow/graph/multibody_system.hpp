#pragma once
// The equations of motion of a set of rigid bodies joined by compliant joints:
//   r' = v,  q' = q (x) (0, w) / 2,  m v' = F,  J w' = T - w x J w
// as an ODE system for the generic methods (dimension(), rhs()).
// Each body sums gravity, then its loads in global load order, then its joint
// forces in global joint order, then user force elements in the order they were
// added, so a body's derivative does not depend on how the model is later partitioned.
#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "mbsflow/graph/force_element.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow {

struct Energy {
  double kinetic = 0.0;
  double gravity = 0.0;  // potential of gravity, -m g . r
  double elastic = 0.0;  // springs, bushings (linear, tables, preload) and force elements
  double total() const { return kinetic + gravity + elastic; }
};

class MultibodySystem {
 public:
  explicit MultibodySystem(const Model& model);
  // Derivatives only for the first `active` bodies (a submodel's own bodies; the rest are
  // ghosts whose state comes from their owners); their values are those of the full model.
  MultibodySystem(const Model& model, int active);

  Eigen::Index dimension() const { return layout_.size(); }
  const StateLayout& layout() const { return layout_; }
  const Model& model() const { return model_; }

  Eigen::VectorXd initial_state() const;
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt);

  // After each completed step: renormalise quaternions and put driven bodies exactly
  // on their prescribed motion. The integrators never touch the state's meaning.
  void after_step(double t, Eigen::VectorXd& y) const;

  Energy energy(double t, const Eigen::VectorXd& y);

  // Adds a user-defined force element (see force_element.hpp).
  void add_force_element(std::shared_ptr<const ForceElement> element);

  // Per joint, 6 numbers: the force and the torque (about body2's attachment point) that
  // the joint exerts on body2, world frame. out is resized to 6 * joints.
  void joint_wrenches(double t, const Eigen::VectorXd& y, Eigen::VectorXd& out);

  // The three phases of rhs(), public so the benchmark can time them apart.
  void update_kinematics(double t, const Eigen::VectorXd& y);
  void compute_joint_forces();  // joints and force elements
  void compute_derivatives(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;

  // The same phases for some bodies or joints only, item by item the same arithmetic: a
  // submodel computes what does not need its neighbours' values while they travel.
  // Joints only, no force elements.
  void kinematics_of(double t, const Eigen::VectorXd& y, std::span<const int> bodies);
  void joint_forces_of(std::span<const int> joints);
  void derivatives_of(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt, std::span<const int> bodies) const;
  void after_step_of(double t, Eigen::VectorXd& y, std::span<const int> bodies) const;

 private:
  struct CompiledJoint {
    int a = 0, b = 0;  // kinematics indices; ground is index n
    bool spring = false;
    bool frame1_identity = true, frame2_identity = true;  // skip the frame products
    int tables = -1;   // index into tables_, -1: linear
    Eigen::Vector3d pa, pb;
    Eigen::Vector4d qfa, qfb;  // joint frame relative to each body
    Eigen::Matrix3d rfa;       // rotation matrix of qfa
    Eigen::Vector3d kt, ct, kr, cr, preload_force, preload_torque;
    double rest_length = 0.0;
  };
  struct Deflection;  // defined in the .cpp
  void body_kinematics(Eigen::Index i, const Eigen::VectorXd& y);
  void drive(const Driver& d, double t);
  void impose(const Driver& d, double t, Eigen::VectorXd& y) const;
  void joint_force(std::size_t k);
  void body_derivative(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  Deflection bushing_deflection(const CompiledJoint& j) const;
  Eigen::Vector3d axis_forces(const CompiledJoint& j, const Eigen::Vector3d& d, int first_axis) const;
  double elastic_energy(const CompiledJoint& j) const;

  Model model_;
  StateLayout layout_;
  Eigen::Index active_ = 0;
  Eigen::Vector3d gravity_;
  std::vector<double> mass_, inv_mass_;
  std::vector<Eigen::Matrix3d> inertia_, inv_inertia_;
  std::vector<CompiledJoint> joints_;
  std::vector<std::array<ForceTable, 6>> tables_;
  // Per body: incident joints (joint * 2 + side, side 1 = body2) in joint order, and loads.
  std::vector<int> incidence_start_, incidence_;
  std::vector<int> load_start_, load_index_;
  std::vector<int> driver_of_body_;  // -1 if free
  // Force elements: their wrenches, and per body the slots into element_out_ in element order.
  std::vector<std::shared_ptr<const ForceElement>> elements_;
  std::vector<std::size_t> element_first_;  // first slot of each element
  std::vector<Wrench> element_out_;
  std::vector<int> element_start_, element_slot_;
  std::vector<Eigen::Vector3d> initial_position_;

  // Kinematics of the current evaluation, n bodies plus ground at index n.
  std::vector<Eigen::Matrix3d> rot_;
  Eigen::Matrix3Xd pos_, vel_, omega_;  // omega in world frame
  Eigen::Matrix4Xd quat_;
  Eigen::Matrix<double, 9, Eigen::Dynamic> joint_out_;  // force on body2, torque on body1, torque on body2
  double time_ = 0.0;

  Kinematics kinematics() const { return Kinematics(rot_, pos_, vel_, omega_); }
};

}  // namespace mbsflow
