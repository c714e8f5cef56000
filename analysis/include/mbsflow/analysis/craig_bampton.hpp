#pragma once
// Craig-Bampton reduction of a finite-element part (docs/flexible.md): the FE model's
// stiffness K and mass M (one row per displacement DOF, both triangles stored) reduced to
// the DOFs of its interface nodes, kept exactly, and the lowest modes of the part held at
// its interface (fixed-interface modes):
//
//   u = T q,  T = [ I  0 ; Psi  Phi ],  Psi = -K_ii^-1 K_ib (constraint modes),
//   K_ii Phi = M_ii Phi diag(omega^2), Phi^T M_ii Phi = I,
//   reduced M_r = T^T M T, K_r = T^T K T,
//
// with b the interface DOFs and i the others. Held at its interface, the reduced part has
// exactly the FE model's lowest fixed-interface frequencies (those kept); free, its
// frequencies converge to the FE model's from above as modes are added. The rigid-body
// motions are in the span of the constraint modes, so the reduced part's mass, centre of
// mass and inertia are the FE model's. Sparse Cholesky (CHOLMOD, supernodal) of K_ii and a
// shift-invert Lanczos (Spectra) on it: no dense matrix of the FE model's size is formed.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include "mbsflow/graph/flexible_body.hpp"

namespace mbsflow {

// One displacement DOF of an FE model: its node's number and direction (1, 2, 3: x, y,
// z; 4, 5, 6: rotations about them, for structural elements).
struct FeDof {
  long node = 0;
  int direction = 1;
  bool operator==(const FeDof&) const = default;
};

// Per node, the rows of its DOFs in `dofs` by direction (direction d at d - 1; -1 where
// the node has no such DOF).
std::unordered_map<long, std::array<Eigen::Index, 6>> dof_rows_by_node(const std::vector<FeDof>& dofs);

// An FE model's matrices: row/column k of each is dof k. Symmetric, both triangles stored.
struct FeMatrices {
  Eigen::SparseMatrix<double> stiffness, mass;
  std::vector<FeDof> dofs;
};

// Mass, centre of mass and inertia tensor (about the centre of mass) of the mass matrix M
// over nodes at `position` (the translational DOFs): integrals of rho over the part of 1,
// x and x x^T, exact for a consistent or lumped mass matrix whose interpolation holds
// linear fields.
struct MassProperties {
  double mass = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

// The fields that measure a reduced body's rigid motion: per translational DOF of the FE
// model, the unit translations along x, y, z (columns 0-2) and the small rotations about
// axes through `centre` (columns 3-5, e_k x (x - centre)); rotational DOFs get the
// rotations' unit values. n_dofs x 6.
Eigen::MatrixXd rigid_body_fields(const std::vector<FeDof>& dofs, const std::vector<Eigen::Vector3d>& dof_position,
                                  const Eigen::Vector3d& centre);

MassProperties mass_properties(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position);

struct CraigBamptonOptions {
  std::vector<long> interface_nodes;  // every DOF of these nodes is kept
  int modes = 10;                     // fixed-interface modes
  std::function<void(const char*)> phase;  // told as each phase begins (progress of a long reduction)
};

struct ReducedPart {
  std::vector<FeDof> interface_dofs;  // the first coordinates of the reduced part, in this order
  int modes = 0;                      // then this many modal coordinates
  Eigen::MatrixXd mass, stiffness;    // reduced, (interface DOFs + modes) squared, symmetric
  Eigen::VectorXd fixed_frequency;    // Hz, of the fixed-interface modes kept (ascending)
  // The FE model's DOFs moved by each reduced coordinate (T), n_dofs x coordinates: row k
  // is dof k of the FE model.
  Eigen::MatrixXd shapes;
  MassProperties properties;          // of the FE model (the reduced part has the same)
  // Rigid-body fields' couplings with the reduced coordinates: 6 x coordinates, rows the
  // translations along x, y, z and rotations about axes through the centre of mass
  // (R^T M T, the linear inertia invariants of a floating frame).
  Eigen::MatrixXd rigid_coupling;
  // The free elastic modes and inertia invariants that move it on a floating frame
  // (floating_frame below); no modes where it has more than max_floating_modes.
  FloatingFrameData floating;
};

// The most elastic coordinates (reduced coordinates less six) a flexible body takes: its
// quadratic inertia invariants grow with their square.
inline constexpr int max_floating_modes = 60;

// The floating frame's data of a reduced part (flexible_body.hpp), from the FE model it
// was reduced from: the free part's elastic modes (every reduced coordinate but the six
// rigid motions), and its inertia invariants from the FE mass matrix.
FloatingFrameData floating_frame(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position, const ReducedPart& part);

// InputError naming the node for an interface node with no DOF in the model or one named
// twice, a part that its interface does not hold (K_ii not positive definite: a solid part
// held at fewer than three nodes off a line), or more modes than interior DOFs.
ReducedPart craig_bampton(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position,
                          const CraigBamptonOptions& options);

// A face of the part tied rigidly to a master node (an RBE2 "spider"): the face nodes'
// DOFs are replaced by the master's six (translations and small rotations at `centre`),
// as an interface node that carries a whole face into a joint. `tie` maps the model's
// DOFs to the tied model's: u = tie * u_tied.
struct TiedModel {
  FeMatrices fe;                              // the face DOFs gone, the master's six last
  std::vector<Eigen::Vector3d> dof_position;  // of the tied model's DOFs
  Eigen::SparseMatrix<double> tie;            // model DOFs x tied DOFs
};
TiedModel tie_rigidly(const FeMatrices& fe, const std::vector<Eigen::Vector3d>& dof_position, const std::vector<long>& face_nodes,
                      long master, const Eigen::Vector3d& centre);

// The frequencies (Hz, ascending) of the reduced part, free (the interface DOFs free) or
// held at its interface (the modal block alone): dense, for checks and reports. Rigid-body
// motions of a free part come out as frequencies near zero.
Eigen::VectorXd reduced_frequencies(const ReducedPart& part, bool held);

}  // namespace mbsflow
