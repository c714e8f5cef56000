#pragma once
// Finite-element input for mbsflow reduce (docs/flexible.md): a CalculiX (Abaqus-style)
// input deck's nodes, elements and node sets, the mass and stiffness matrices that
// CalculiX writes with `*FREQUENCY, SOLVER=MATRIXSTORAGE` (JOB.sti, JOB.mas, JOB.dof), or
// the same as Matrix Market files with a DOF map, and the outer faces of the mesh drawn
// for the reduced part.
#include <Eigen/Core>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "mbsflow/analysis/craig_bampton.hpp"

namespace mbsflow {

struct FeElement {
  std::string type;         // upper case, as the deck names it (C3D8, C3D20R, S4, ...)
  std::vector<long> nodes;  // in the element's node order
};

struct FeMesh {
  std::vector<long> node_id;
  std::vector<Eigen::Vector3d> node_position;
  std::unordered_map<long, std::size_t> node_index;  // node number -> index in node_id
  std::vector<FeElement> elements;
  std::map<std::string, std::vector<long>> node_sets;  // names upper case
};

// *NODE, *ELEMENT, *NSET (lists of nodes or sets, or GENERATE) and *INCLUDE of a deck;
// other keywords are passed over. InputError with file:line for what cannot be read.
FeMesh read_fe_deck(const std::string& path);

// JOB.sti, JOB.mas and JOB.dof as CalculiX writes them: "row column value" lines, one
// triangle of each symmetric matrix (the other is filled in here), and "node.direction"
// per row. InputError naming the file for a missing file or a bad line.
FeMatrices read_calculix_matrices(const std::string& job);

// Matrix Market coordinate files (real, symmetric or general) and a DOF map in the .dof
// form (one "node.direction" line per row).
FeMatrices read_matrix_market(const std::string& stiffness, const std::string& mass, const std::string& dof_map);

// The faces of the mesh that belong to one solid element only, and the shell elements:
// triangles of node numbers (quadrilaterals split in two), the corner nodes only.
std::vector<std::array<long, 3>> outer_triangles(const FeMesh& mesh);

// Node numbers from "12 15-20 31" or "12,15-20" (ranges inclusive) or a node set's name.
std::vector<long> parse_node_list(const std::string& text, const FeMesh& mesh);

}  // namespace mbsflow
