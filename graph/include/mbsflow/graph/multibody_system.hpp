#pragma once
// The equations of motion of a set of rigid bodies joined by compliant and rigid joints:
//   r' = v,  q' = q (x) (0, w) / 2,  m v' = F + F_c,  J w' = T + T_c - w x J w
// as an ODE system for the generic methods (dimension(), rhs()). F_c, T_c are the
// reactions of the rigid joints: bodies joined by rigid joints form a cluster whose
// multipliers come from one sparse solve per evaluation (index-1 form, see
// rigid_cluster.hpp); after_step() projects each cluster's positions and velocities back
// onto its constraints, so drift never accumulates.
// Each body sums gravity, then its loads in global load order, then its joint
// forces in global joint order, then user force elements in the order they were
// added, so a body's derivative does not depend on how the model is later partitioned.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mbsflow/graph/force_element.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow {

template <class S>
struct BodyMotionT;  // constraint_rows.hpp
using BodyMotion = BodyMotionT<double>;
struct JointGeometry;  // constraint_rows.hpp
template <class S>
struct ConstraintRowT;  // constraint_rows.hpp
using ConstraintRow = ConstraintRowT<double>;
struct FlexibleSlots;  // multibody_constraints.hpp
struct FlexibleAt;     // flexible_state.hpp
class RigidCluster;    // rigid_cluster.hpp
struct BodyFrameView;  // force_laws.hpp
template <class S>
struct BodyFrameT;  // force_laws.hpp

namespace detail {
// Owns a T that this header does not define and copies it deeply (the copy and destroy
// functions come from where T is defined).
template <class T>
class DeepPtr {
 public:
  DeepPtr() = default;
  DeepPtr(T* p, T* (*copy)(const T&), void (*destroy)(T*)) : p_(p), copy_(copy), destroy_(destroy) {}
  DeepPtr(const DeepPtr& o) : p_(o.p_ ? o.copy_(*o.p_) : nullptr), copy_(o.copy_), destroy_(o.destroy_) {}
  DeepPtr(DeepPtr&& o) noexcept : p_(std::exchange(o.p_, nullptr)), copy_(o.copy_), destroy_(o.destroy_) {}
  DeepPtr& operator=(DeepPtr o) noexcept {
    std::swap(p_, o.p_);
    std::swap(copy_, o.copy_);
    std::swap(destroy_, o.destroy_);
    return *this;
  }
  ~DeepPtr() {
    if (p_) destroy_(p_);
  }
  T* operator->() const { return p_; }
  T& operator*() const { return *p_; }

 private:
  T* p_ = nullptr;
  T* (*copy_)(const T&) = nullptr;
  void (*destroy_)(T*) = nullptr;
};
}  // namespace detail

struct Energy {
  double kinetic = 0.0;
  double gravity = 0.0;  // potential of gravity, -m g . r
  double elastic = 0.0;  // springs, bushings (linear, tables, preload) and force elements
  double total() const { return kinetic + gravity + elastic; }
};

// A body's inertia tensor (Body::inertia: Ixx, Iyy, Izz, Ixy, Ixz, Iyz) as a matrix.
Eigen::Matrix3d inertia_matrix(const Vec6& inertia);

// Whether the whole-model system of m has an analytic Jacobian (see
// MultibodySystem::has_analytic_jacobian), without building it.
bool has_analytic_jacobian(const Model& m, std::string* why = nullptr);

class MultibodySystem {
 public:
  explicit MultibodySystem(const Model& model);
  // Derivatives only for the first `active` bodies (a submodel's own bodies; the rest are
  // ghosts whose state comes from their owners); their values are those of the full model.
  MultibodySystem(const Model& model, int active);
  // The same without a copy of the model: moved in, or shared with its other readers
  // (a million-body model is about a gigabyte). Copies of the system share it too.
  MultibodySystem(Model&& model, int active);
  MultibodySystem(std::shared_ptr<const Model> model, int active);

  Eigen::Index dimension() const { return layout_.size(); }
  const StateLayout& layout() const { return layout_; }
  const Model& model() const { return *model_; }

  Eigen::VectorXd initial_state() const;
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt);

  // After each completed step: renormalise quaternions and put driven bodies exactly
  // on their prescribed motion. The integrators never touch the state's meaning.
  void after_step(double t, Eigen::VectorXd& y) const;

  Energy energy(double t, const Eigen::VectorXd& y);

  // Where the modal coordinates of the model's flexible body f start in the state (their
  // rates follow, as many again).
  Eigen::Index flexible_state(std::size_t f) const { return layout_.tail(compiled_->flexible_tail[f]); }
  // The flexible bodies whose frame is listed, ascending (derivatives_of and after_step_of
  // take those, their nodes and modes with the frame).
  std::vector<int> flexible_framed(std::span<const int> bodies) const;

  // Adds a user-defined force element (see force_element.hpp).
  void add_force_element(std::shared_ptr<const ForceElement> element);

  // Per joint, 6 numbers: the force and the torque (about body2's attachment point) that
  // the joint exerts on body2, world frame, rigid joints' reactions included. out is
  // resized to 6 * joints.
  void joint_wrenches(double t, const Eigen::VectorXd& y, Eigen::VectorXd& out);
  // Per joint, the effort of its motor (torque or force along the joint axis on body2;
  // 0 without a motor), at the state of the last joint_wrenches() call.
  const Eigen::VectorXd& motor_efforts() const { return motor_effort_; }

  // Bodies joined by rigid joints, one list per cluster (ascending system indices);
  // cluster_of(body) is its cluster or -1. A partitioned run keeps a cluster together.
  int clusters() const;
  const std::vector<int>& cluster_bodies(int cluster) const;
  int cluster_of(int body) const;
  // Largest violation of a rigid joint's position constraints at y (0 without any), and
  // which joint has it.
  double constraint_violation(double t, const Eigen::VectorXd& y, int* joint = nullptr) const;
  // The value of each of constraint_jacobian's rows at y (0 for a row on velocities), with
  // the flexible bodies' nodes placed where their frames and modes put them.
  Eigen::VectorXd constraint_values(double t, const Eigen::VectorXd& y) const;
  // The rigid joints' constraint rows at y (their motors' rows included), each a row over
  // the bodies' 6 velocity coordinates (velocity and angular velocity, world frame) at
  // columns 6 i .. 6 i + 5 of body i: C v = 0 holds the joints. joint_of_row, if given,
  // gets each row's joint index. For linearisations (the analysis layer).
  Eigen::SparseMatrix<double> constraint_jacobian(double t, const Eigen::VectorXd& y,
                                                  std::vector<int>* joint_of_row = nullptr) const;

  // The structural non-zeros of d rhs / d y (values 1), following the body graph: a body's
  // accelerations depend on its own state and on the states of the bodies it shares a
  // joint or a force element with, and a rigid cluster's bodies on all that any of them
  // depends on; its position and quaternion rates on its own velocities and orientation.
  // The implicit methods difference the Jacobian by this pattern's column colouring and
  // factor it as a sparse matrix.
  Eigen::SparseMatrix<double> jacobian_pattern() const;
  // Whether jacobian() can give d rhs / d y: no user force element other than constant
  // wrenches (those have no analytic Jacobian; the methods then difference by the
  // pattern's colouring), and the system is the whole model. Else *why says which item
  // stands in the way.
  bool has_analytic_jacobian(std::string* why = nullptr) const;
  // d rhs / d y at (t, y), exact up to rounding (forward-mode differentiation of each
  // element's force law and of the rigid joints' constraint rows, assembled body by body
  // along the body graph, and through each rigid cluster's reactions), written into jac,
  // a matrix of jacobian_pattern()'s pattern. Throws std::logic_error without one.
  // parallel: runs body(begin, end) over [0, count) split as it likes (a caller with a
  // thread pool passes its parallel loop); the joints' derivatives, and from the second
  // call on the bodies' rows where the model has no rigid clusters or flexible bodies, go
  // through it, each written to its own place, so the matrix is the same whatever the
  // split. Empty: serial.
  // velocity_columns = false: the columns of the velocities and angular velocities are
  // not computed (they hold zeros or some of their terms), for a caller at rest that needs
  // the stiffness alone: the joints' derivatives in about half the work.
  using ParallelFor = std::function<void(std::size_t count, const std::function<void(std::size_t begin, std::size_t end)>& body)>;
  void jacobian(double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac, const ParallelFor& parallel = nullptr,
                bool velocity_columns = true);

  // Bytes this system holds: what the model compiles to (shared by its copies) and its own
  // workspace (the kinematics and joint outputs of an evaluation, constraint scratch),
  // from the containers' capacities. The model itself is not counted.
  struct MemoryUse {
    std::size_t compiled = 0, workspace = 0;
  };
  MemoryUse memory_use() const;

  // The three phases of rhs(), public so the benchmark can time them apart. The first
  // keeps the bodies' rotation matrices only where the model has something that reads them
  // other than the lane kernels (which compute their own from the quaternions): a joint off
  // the lanes, a load, a force element. update_kinematics keeps all of them (energies,
  // Jacobians and joint reactions read them).
  void kinematics_for_rhs(double t, const Eigen::VectorXd& y);
  void update_kinematics(double t, const Eigen::VectorXd& y);
  void compute_joint_forces();  // joints and force elements
  void compute_derivatives(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;

  // The same phases for some bodies or joints only, item by item the same arithmetic: a
  // submodel computes what does not need its neighbours' values while they travel.
  // Joints only, no force elements. A listed frame brings in its flexible body (nodes, modes).
  void kinematics_of(double t, const Eigen::VectorXd& y, std::span<const int> bodies);
  void joint_forces_of(std::span<const int> joints);
  void derivatives_of(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt, std::span<const int> bodies) const;
  void after_step_of(double t, Eigen::VectorXd& y, std::span<const int> bodies) const;

 private:
  // A bushing's or spring's force law and a joint's frames, as the model gives them. Joints
  // with the same (every bushing of a generated chain or grid) share one: the compiled
  // joints stay small, and the lane kernels load one law for several joints.
  struct JointLaw {
    bool spring = false;
    bool frame1_identity = true, frame2_identity = true;  // skip the frame products
    Eigen::Vector3d pa, pb;
    Eigen::Vector4d qfa, qfb;  // joint frame relative to each body
    Eigen::Matrix3d rfa;       // rotation matrix of qfa
    Eigen::Vector3d kt, ct, kr, cr, preload_force, preload_torque;
    double rest_length = 0.0;
  };
  struct CompiledJoint {
    int a = 0, b = 0;  // kinematics indices; ground is index n
    int law = 0;       // index into the compiled laws
    int kinematic = -1;  // index into the constraints' joint geometry; -1: bushing or spring
    int tables = -1;     // index into tables_, -1: linear
    bool rigid = false;
    bool applies_force = false;  // kinematic: compliant, a limit stop or an effort motor
  };
  const JointLaw& law_of(const CompiledJoint& j) const { return compiled_->laws[static_cast<std::size_t>(j.law)]; }
  // A body's mass properties (body frame), shared like the joints' laws.
  struct BodyLaw {
    double mass = 0.0, inv_mass = 0.0;
    Eigen::Matrix3d inertia, inv_inertia;
  };
  const BodyLaw& body_law(std::size_t i) const {
    return compiled_->body_laws[static_cast<std::size_t>(compiled_->body_law[i])];
  }
  struct Constraints;  // multibody_constraints.cpp
  void compile_constraints();
  std::size_t constraint_bytes() const;  // the constraints' containers (a cluster's own solver not counted)
  void kinematic_joint_force(std::size_t k);
  const JointGeometry& geometry_of(const CompiledJoint& j) const;  // a kinematic joint's
  double kinematic_energy(const CompiledJoint& j) const;
  void unconstrained_cluster(int c, double t, const Eigen::VectorXd& y) const;
  void solve_cluster(int c, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  // jacobian()'s part for rigid cluster c (cluster_jacobian.cpp). unconstrained[s]: for
  // each body b that the cluster's body s reads, d (v', w') / d (state of b) under the
  // applied forces alone; dydt: the rates at (t, y), just evaluated. column(b, k, rates)
  // gets, for state number k (0..12) of each free body b that any body of the cluster
  // reads, the derivatives of the 6 rates (v', w') of each of the cluster's bodies.
  using RateBlocks = std::vector<std::pair<int, Eigen::Matrix<double, 6, 13>>>;
  void cluster_jacobian(int c, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& dydt,
                        const std::vector<RateBlocks>& unconstrained,
                        const std::function<void(int body, int k, const Eigen::VectorXd& rates)>& column) const;
  // jacobian()'s part for a rigid cluster that holds flexible bodies or whose bodies read
  // a flexible body's modes (flexible_cluster_jacobian.cpp). wrench_of(body, value, parts):
  // the applied wrench on a body (world force, torque) and its derivatives by the state
  // numbers it reads, each as (index in y, derivative); write(col, row, count, values):
  // the derivatives by y[col] of the rates at rows row..row+count-1.
  using WrenchParts = std::vector<std::pair<Eigen::Index, Eigen::Matrix<double, 6, 1>>>;
  void flexible_cluster_jacobian(int c, double t, const Eigen::VectorXd& y, const Eigen::VectorXd& dydt,
                                 const std::function<void(int body, Eigen::Matrix<double, 6, 1>& value, WrenchParts& parts)>& wrench_of,
                                 const std::function<void(Eigen::Index col, Eigen::Index row, int count, const double* values)>& write) const;
  BodyMotion motion_at(int i) const;  // kinematics index i of the current evaluation
  // Each rigid joint's constraint rows at y, in constraint_jacobian's order.
  void for_each_rigid_row(double t, const Eigen::VectorXd& y, const std::function<void(const CompiledJoint&, std::size_t joint,
                                                                                       const ConstraintRow&)>& row) const;
  std::vector<int> clusters_of(std::span<const int> bodies) const;  // ascending, each once
  void add_reactions(Eigen::VectorXd& out);
  void project_cluster(int c, double t, Eigen::VectorXd& y) const;
  // mu <- -(phi') of the cluster's rows (evaluated at y's positions) at y's velocities.
  void velocity_violations(const RigidCluster& rc, const Eigen::VectorXd& y, Eigen::VectorXd& mu) const;
  void applied_wrench(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::Vector3d& force, Eigen::Vector3d& torque) const;
  void write_derivative(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt,
                        const Eigen::Vector3d& force, const Eigen::Vector3d& torque) const;
  // list[0..n), or 0..n-1 when null; every rotation matrix, or those the model reads.
  void kinematics_in(const int* list, std::size_t n, const Eigen::VectorXd& y, bool all_rotations);
  void make_workspace();  // at the first evaluation (kinematics_in)
  // Kernels on Lanes (lane_kernels.cpp), each for Lanes::width items: two (SSE2) or, with
  // the suffix _avx, four (AVX).
  void bushings_on_lanes(const int* joints);
  void bushings_on_lanes_avx(const int* joints);
  void kinematics_on_lanes(const int* bodies, const Eigen::VectorXd& y, bool rotations);
  void kinematics_on_lanes_avx(const int* bodies, const Eigen::VectorXd& y, bool rotations);
  // A free body's rates from its applied force and torque (wrench: 6 per lane).
  void rates_on_lanes(const int* bodies, const double* wrench, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  void rates_on_lanes_avx(const int* bodies, const double* wrench, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  template <int Width>
  void free_bodies_on_lanes(const int* bodies, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  void derivatives_in(const int* list, std::size_t n, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  void drive(const Driver& d, double t);
  // The flexible bodies (flexible_system.cpp): compiled with the system, their nodes'
  // kinematics from the frame and the modes, the rates of frame and modes, the nodes'
  // states put where the frame says, the energies.
  void compile_flexible();
  void follow_flexible(const Eigen::VectorXd& y);
  void follow_nodes_of(std::size_t f, const Eigen::VectorXd& y);
  void flexible_derivatives(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  void flexible_derivative(std::size_t f, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  // Flexible body f's applied generalised force (6 + ne: frame force and torque in its
  // axes, modal forces), its accelerations xi' under it alone, and its rates from xi' (at:
  // its coordinates as this evaluation read them from y).
  Eigen::VectorXd flexible_force(std::size_t f, const FlexibleAt& at, double t, const Eigen::VectorXd& y) const;
  Eigen::VectorXd free_flexible_accelerations(std::size_t f, const FlexibleAt& at, const Eigen::VectorXd& y,
                                              const Eigen::VectorXd& q) const;
  void write_flexible_rates(std::size_t f, const FlexibleAt& at, const Eigen::VectorXd& xi_rate, const Eigen::VectorXd& y,
                            Eigen::VectorXd& dydt) const;
  // Whether body i is a flexible body's node (its motion follows the frame and the modes).
  bool follows_frame(std::size_t i) const {
    if (compiled_->flexible_of_body.empty() || compiled_->flexible_of_body[i] < 0) return false;
    return model().flexible[static_cast<std::size_t>(compiled_->flexible_of_body[i])].frame != static_cast<int>(i);
  }
  void place_flexible_nodes(Eigen::VectorXd& y) const;
  void place_nodes_of(std::size_t f, Eigen::VectorXd& y) const;
  // A rigid cluster that holds flexible bodies (flexible_joints.cpp): solved and projected
  // in the generalised velocities of its rigid bodies and flexible bodies.
  // Where a rigid joint touches a flexible body, its frame and every such body of it are
  // made one piece (touched: per body, whether a rigid joint holds it; piece: per body, its
  // rigid piece); a cluster's slots in generalised velocities.
  void join_flexible_pieces(std::vector<char>& touched, std::vector<int>& piece) const;
  FlexibleSlots flexible_slots(const std::vector<int>& bodies) const;
  void solve_flexible_cluster(int c, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  void project_flexible_cluster(int c, double t, Eigen::VectorXd& y) const;
  void flexible_energy(const Eigen::VectorXd& y, Energy& e) const;
  bool flexible_owned(Eigen::Index i) const {
    return !compiled_->flexible_of_body.empty() && compiled_->flexible_of_body[static_cast<std::size_t>(i)] >= 0;
  }
  void impose(const Driver& d, double t, Eigen::VectorXd& y) const;
  void joint_force(std::size_t k);
  void joint_forces_in(const int* list, std::size_t n);  // list[0..n), or 0..n-1 when list is null
  bool on_lanes(const CompiledJoint& j) const;  // a bushing the lane kernels take
  void body_derivative(Eigen::Index i, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const;
  BodyFrameView body_frame_at(int i) const;  // kinematics index i of the current evaluation
  const std::array<ForceTable, 6>* tables_of(const CompiledJoint& j) const {
    return j.tables >= 0 ? &compiled_->tables[static_cast<std::size_t>(j.tables)] : nullptr;
  }
  template <class Frame>
  double elastic_energy(const CompiledJoint& j, const Frame& a, const Frame& b) const;  // not a kinematic joint
  BodyFrameT<double> frame_from_state(int i, const Eigen::VectorXd& y) const;

  std::shared_ptr<const Model> model_;
  StateLayout layout_;
  Eigen::Index active_ = 0;
  Eigen::Vector3d gravity_;
  // What the model compiles to: read by every evaluation, written only while the system
  // is built (or a force element is added). Copies of a system share it, each with its own
  // workspace below: the results writer's copy of a million-body system would otherwise
  // hold a copy of its own. add_force_element copies it first if it is shared.
  struct Compiled {
    std::vector<int> body_law;       // per body, index into body_laws
    std::vector<BodyLaw> body_laws;  // each distinct one once
    std::vector<CompiledJoint> joints;
    std::vector<JointLaw> laws;  // each distinct one once
    std::vector<std::array<ForceTable, 6>> tables;
    // Per body: incident joints (joint * 2 + side, side 1 = body2) in joint order, and loads.
    std::vector<int> incidence_start, incidence;
    std::vector<int> load_start, load_index;
    std::vector<int> driver_of_body;  // -1 if free
    // Per body, the flexible body it belongs to (frame or node), -1 if none (empty without
    // flexible bodies); per flexible body, where its coordinates start in the state's tail.
    std::vector<int> flexible_of_body;
    std::vector<Eigen::Index> flexible_tail;
    // Force elements, and per body the slots into element_out_ in element order.
    std::vector<std::shared_ptr<const ForceElement>> elements;
    std::vector<std::size_t> element_first;  // first slot of each element
    std::vector<int> element_start, element_slot;
    // Whether an evaluation reads rotation matrices from the workspace (rot_): not where
    // every joint is a lane kernel's bushing and no load or force element acts.
    bool rotations_read = true;
  };
  std::shared_ptr<Compiled> compiled_ = std::make_shared<Compiled>();
  // The prescribed displacement, rate and acceleration of each driver at its last few
  // times: implicit methods and difference Jacobians evaluate many states at one time, and
  // a rough-track driver costs a hundred sines per evaluation.
  struct DriveMemo {
    static constexpr int slots = 4;
    double t[slots] = {NAN, NAN, NAN, NAN};
    Eigen::Vector3d value[slots], rate[slots], accel[slots];
    int next = 0;
    int find(double time) const {  // the slot of time, or -1
      for (int s = 0; s < slots; ++s)
        if (t[s] == time) return s;
      return -1;
    }
  };
  std::vector<DriveMemo> drive_memo_;
  std::vector<Wrench> element_out_;  // the force elements' wrenches of the current evaluation

  // Kinematics of the current evaluation, n bodies plus ground at index n.
  std::vector<Eigen::Matrix3d> rot_;
  Eigen::Matrix3Xd pos_, vel_, omega_;  // omega in world frame
  Eigen::Matrix4Xd quat_;
  Eigen::Matrix<double, 9, Eigen::Dynamic> joint_out_;  // force on body2, torque on body1, torque on body2
  double time_ = 0.0;
  detail::DeepPtr<Constraints> constraints_;
  std::vector<double> jacobian_scratch_;  // jacobian(): each joint's wrench derivatives, kept between calls
  // jacobian(): where its writes land in the matrix's values, in the order it writes them,
  // found by search on the first call and reused while the matrix has the same column
  // starts and every write still lands on its rows (each is checked). body_marks: where
  // each body's writes start among them (and their end), so that bodies may replay theirs
  // on several threads.
  struct JacobianSlots {
    std::vector<int> outer, slots, body_marks;
  };
  JacobianSlots jacobian_slots_;
  Eigen::VectorXd motor_effort_;

  Kinematics kinematics() const { return Kinematics(rot_, pos_, vel_, omega_); }
};

}  // namespace mbsflow
