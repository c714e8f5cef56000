#pragma once
// A reduced finite-element body on a floating frame of reference (docs/flexible.md).
//
// The frame is a body of the model (its state the 13 numbers of any body): origin at the
// part's undeformed centre of mass, axes the FE model's turned by the body's orientation.
// The part deforms by ne elastic modal coordinates eta (the free-free modes of the
// Craig-Bampton part, mass-normalised and orthogonal to its rigid motions), which sit in
// the state's tail with their rates. Its interface nodes are bodies too ("frame@ID", no
// mass of their own), whose motion follows the frame and the modes: joints, bushings and
// loads attach to them as to any body, and what they exert returns to the frame and the
// modes as generalised forces.
//
// Equations of motion (Lagrange in the frame's quasi-velocities xi = [v_b, w, eta']):
//   M(eta) xi' = Q + Q_v,  M = [[m I, M_tr, M_te], [., M_rr, M_re], [., ., I]],
// with every inertia coupling of the frame's rotation and the deformation (the velocity
// of a point is v + w x (x0 + u) + u', u = Phi eta), Q_v the quadratic velocity terms
// -M' xi - [w x p_t; w x p_r + v_b x p_t; -1/2 xi^T dM/deta_k xi] (p = M xi), Q the
// applied forces, -K eta - D eta' on the modes. Valid for large motion, small
// deformation; the reduced body has no geometric stiffening.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace mbsflow {

// What the reduction gives the floating frame (mbsflow reduce writes it, /floating).
// Every vector and matrix in the part's axes, lengths from its centre of mass.
struct FloatingFrameData {
  double mass = 0.0;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about the centre of mass
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();   // in the FE model's coordinates
  Eigen::VectorXd omega2;                             // ne: the elastic modes' (rad/s)^2
  // The inertia invariants (G: the rigid fields of the FE DOFs at the undeformed shape,
  // G_k the change of their rotation columns per unit eta_k, U: the modes' displacements,
  // M: the FE mass matrix):
  Eigen::MatrixXd mass0;             // (6 + ne)^2: [G U]^T M [G U] at eta = 0
  std::vector<Eigen::Matrix<double, 3, 6>> a;  // per k: G_k^T M G (rotation rows)
  std::vector<Eigen::Matrix3d> c;    // per k, l (k * ne + l): G_k^T M G_l
  std::vector<Eigen::MatrixXd> e;    // per k: G_k^T M U, 3 x ne
  // Interface nodes: id, position (from the centre), and per node its translation (rows
  // 0-2) and small rotation (rows 3-5) per unit of each modal coordinate, 6 x ne (rotations
  // zero at a node with no rotation DOFs: it turns with the frame).
  std::vector<long> node_id;
  std::vector<Eigen::Vector3d> node_position;
  std::vector<Eigen::MatrixXd> node_shape;
  // The elastic modes in the reduced coordinates (R x ne), where the reduction made them.
  Eigen::MatrixXd reduced_modes;
  // The part's drawn surface (mbsflow reduce's /display), for the results' deformed shape:
  // its points (from the centre, part axes), their displacement per modal coordinate
  // (3 d x ne, point by point), its triangles (3 point indices each). Empty where the
  // part file has none.
  Eigen::Matrix3Xd display_position;
  Eigen::MatrixXd display_shape;
  std::vector<int> display_triangle;
  int modes() const { return static_cast<int>(omega2.size()); }
};

// A flexible body of a model: its frame body, its node bodies (in node_id's order), where
// its coordinates sit in the state's tail, and its modal damping (eta'' + ... + D eta').
struct FlexibleBody {
  std::string name;
  int frame = 0;
  std::vector<int> nodes;
  std::shared_ptr<const FloatingFrameData> data;
  Eigen::VectorXd damping;  // per mode: the modal damping coefficient 2 zeta omega (1/s)
  Eigen::VectorXd initial_eta, initial_eta_rate;  // empty: undeformed, at rest
  std::string source;       // the model file's item, written back as it was given
};

// Where each flexible body's coordinates start in the state's tail (2 ne each, in the
// list's order), and the tail's length last: one more entry than bodies.
std::vector<Eigen::Index> flexible_tail_offsets(const std::vector<FlexibleBody>& flexible);

// The mass matrix M(eta) of the frame's quasi-velocities and the modes, (6 + ne)^2.
Eigen::MatrixXd flexible_mass_matrix(const FloatingFrameData& d, const Eigen::VectorXd& eta);

// xi' (6 + ne) from the state of the frame (body-frame velocity v_b, angular velocity w),
// the modal coordinates and rates, and the applied generalised force q (6 + ne: force and
// torque about the frame's origin in the body frame, then the modal forces, the elastic
// and damping forces not included).
Eigen::VectorXd flexible_accelerations(const FlexibleBody& f, const Eigen::Vector3d& v_b, const Eigen::Vector3d& w,
                                       const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate, const Eigen::VectorXd& q);

// The kinetic energy 1/2 xi^T M(eta) xi and the strain energy 1/2 eta^T K eta.
double flexible_kinetic_energy(const FloatingFrameData& d, const Eigen::Vector3d& v_b, const Eigen::Vector3d& w,
                               const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate);
double flexible_strain_energy(const FloatingFrameData& d, const Eigen::VectorXd& eta);

// Node k's place and small rotation in the frame (body axes, from the origin) and their
// rates, at eta, eta'.
struct NodeMotion {
  Eigen::Vector3d position, rotation, velocity, angular_velocity;
};
NodeMotion flexible_node_motion(const FloatingFrameData& d, int node, const Eigen::VectorXd& eta, const Eigen::VectorXd& eta_rate);

// The drawn surface (display_*) in the world, its frame at `origin` turned by r, deformed
// by eta: a column per point; in *elastic, if given, their elastic displacement alone
// (world axes). The results' XDMF sidecar and the browser viewer draw it so.
Eigen::Matrix3Xd flexible_surface_points(const FloatingFrameData& d, const Eigen::Vector3d& origin, const Eigen::Matrix3d& r,
                                         const Eigen::VectorXd& eta, Eigen::Matrix3Xd* elastic = nullptr);

}  // namespace mbsflow
