#pragma once
// The file that mbsflow reduce writes (docs/flexible.md), one HDF5 file:
//   /reduced/mass, /reduced/stiffness (R x R, R = interface DOFs + modes; kg, N/m and
//     their rotational kin), /reduced/coordinate_dof (R x 2: node, direction 1..6 of each
//     interface coordinate; node 0, direction 0 for a modal one)
//   /modes/frequency (K, Hz: the fixed-interface modes kept)
//   /mass/mass (1, kg), /mass/centre (3, m), /mass/inertia (3 x 3, kg m^2, about the centre)
//   /invariants/rigid_coupling (6 x R: translations x, y, z and rotations about the centre
//     against each reduced coordinate, R^T M T)
//   /nodes/id (N), /nodes/position (N x 3, m): every node of the deck
//   /interface/node (nodes of the interface, in the coordinates' order)
//   /display/node (D: indices into /nodes of the nodes drawn), /display/position (D x 3),
//     /display/triangle (F x 3: indices into /display/node), /display/shape (R x D x 3: each
//     display node's displacement per unit of each reduced coordinate, m)
//   /xdmf: the views of the XDMF sidecar PATH.xdmf written beside it, which ParaView's
//     default reader opens: time q is coordinate q (1-based), the outer surface with that
//     coordinate's shape as a point vector (Warp By Vector draws it)
// with the program version, the deck and the command line as attributes.
#include <string>

#include "mbsflow/analysis/craig_bampton.hpp"
#include "mbsflow/io/fe_input.hpp"

namespace mbsflow {

struct ReducedPartInfo {
  std::string source;        // the deck
  std::string command_line;
};

// Written under PATH.part and renamed when complete. `mesh`: the deck (its nodes, and its
// outer faces drawn); the shapes come from part.shapes and `dofs`, the FE model's DOFs.
void write_reduced_part(const std::string& path, const ReducedPart& part, const std::vector<FeDof>& dofs,
                        const FeMesh& mesh, const ReducedPartInfo& info);

// What a reduced part file holds for the model and the checks: the reduced matrices,
// frequencies, mass properties and coupling, the interface DOFs (InputError for a file
// that is not one).
// `info`, if given, gets the deck and command line it was made from.
ReducedPart read_reduced_part(const std::string& path, ReducedPartInfo* info = nullptr);

// "rigid-body motions at f1 .. f6 Hz, then f7, .. f12 Hz": the free reduced part's six
// rigid-body motions (at rounding's level) and its lowest elastic frequencies, as mbsflow
// reduce and mbsflow info report them.
std::string free_frequencies_text(const ReducedPart& part);

// Whether the file at path is one that mbsflow reduce wrote (false for anything else).
bool is_reduced_part(const std::string& path);

}  // namespace mbsflow
