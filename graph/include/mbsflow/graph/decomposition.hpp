#pragma once
// Cutting a model into weakly coupled submodels. Two partitioners: the seed's (the
// body/joint graph in a bandwidth-reducing order, reverse Cuthill-McKee per connected
// part, cut into K contiguous pieces of equal cost) and METIS k-way (balanced cost, fewest
// cut joints). Each piece gets its boundary (ghost) bodies and an exchange plan.
#include <string>
#include <string_view>
#include <vector>

#include "mbsflow/graph/model.hpp"
#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow {

// Bandwidth-reducing order of the bodies (reverse Cuthill-McKee on the joint graph; the
// connected parts one after another).
std::vector<int> cuthill_mckee_order(const Model& model);

// Bodies joined by rigid joints form pieces that no partition cuts: the piece of each
// body, numbered in the order of their first body (a body without rigid joints is a piece).
std::vector<int> rigid_pieces(const Model& model);

// The pieces no partition cuts: the rigid pieces, and each flexible body's frame and nodes
// together with every body joined to a node (by a joint or a force element). A node's
// motion is its part's, which a neighbour could not compute from a ghost's 13 numbers;
// joints at a part's frame may be cut. Numbered as rigid_pieces numbers them.
std::vector<int> uncut_pieces(const Model& model);
// Per body, the flexible body whose uncut piece holds it (its frame, its nodes and what is
// joined to them), -1 for none.
std::vector<int> flexible_piece_of(const Model& model);

// Relative cost of computing a body (its own equations plus half of each joint; a flexible
// body's frame carries its part's, hundreds of rigid bodies' worth).
std::vector<double> body_costs(const Model& model);

enum class Partitioner {
  best,   // both, keep the one whose slowest submodel is estimated fastest
  band,   // reverse Cuthill-McKee band cut into pieces of equal cost (the seed's)
  metis,  // METIS k-way
};
const char* partitioner_name(Partitioner p);

struct Submodel {
  std::vector<int> own;  // global body indices, ascending
  // Bodies of other submodels integrated here as well (an overlap, see with_overlap):
  // their derivatives are computed here, their values come from their owners at each
  // exchange. Empty in a plain decomposition.
  std::vector<int> borrowed;
  std::vector<int> ghosts;  // bodies of other submodels joined to own or borrowed bodies, ascending
  std::vector<int> joints;  // joints with at least one own or borrowed body, ascending global index
  std::vector<int> flexible;  // the model's flexible bodies whose bodies are own here, ascending
  int cut_joints = 0;       // of those, the ones that reach a ghost
  double cost = 0.0;
  // Per neighbour that owns some of this submodel's borrowed bodies or ghosts: which of its
  // bodies (its local indices) fill which slots here (local indices), in ascending global order.
  struct Exchange {
    int neighbour = 0;
    std::vector<int> from;  // the neighbour's local indices
    std::vector<int> to;    // this submodel's local borrowed or ghost slots
    std::vector<int> near;  // positions in from/to of the bodies joined to own bodies
  };
  std::vector<Exchange> exchanges;
  // Own bodies first, then borrowed ones, then ghosts; -1 if none of them.
  int local_index(int global) const;
  // Bodies whose derivatives are computed here: own and borrowed.
  int integrated() const { return static_cast<int>(own.size() + borrowed.size()); }
  // Estimated stage time (ns): its cost, plus the other half of each cut joint (computed
  // on both sides) and the copying of ghosts.
  double estimated_time() const { return cost + 39.0 * cut_joints + 10.0 * static_cast<double>(ghosts.size()); }
};

struct Decomposition {
  std::vector<int> part_of_body;
  std::vector<Submodel> submodels;
  int cut_joints = 0;
  double imbalance = 0.0;  // max cost / mean cost - 1
  // Where each flexible body's modes start in the whole state's tail, and its length last
  // (flexible_tail_offsets; empty without flexible bodies).
  std::vector<Eigen::Index> flexible_tail;
  StateLayout layout() const {
    return {static_cast<Eigen::Index>(part_of_body.size()), flexible_tail.empty() ? 0 : flexible_tail.back()};
  }
  Partitioner partitioner = Partitioner::band;  // which one made it
  double estimated_time() const;  // of the slowest submodel
};


// A partitioner by its name: best, band or metis (InputError naming them).
Partitioner partitioner_named(std::string_view name);

// K-way decomposition that never cuts an uncut piece; InputError if k < 1 or k is more
// than the pieces the rigid joints and flexible bodies leave (the message gives their sizes).
Decomposition decompose(const Model& model, int k, Partitioner partitioner = Partitioner::best);
// Decomposition from a given assignment of bodies to parts 0..k-1 (every part non-empty,
// no rigid joint between two parts, each uncut piece of a flexible body in one part).
Decomposition decompose(const Model& model, const std::vector<int>& part_of_body, int k);

// The decomposition with overlapping submodels, for loose coupling: each submodel also
// integrates (borrows) the bodies of other submodels that a disturbance at its boundary
// reaches within `reach` seconds, a joint taking 1 / (its fastest rate) to cross (see
// joint_rates) and a rigid joint none. Own bodies are those of d; ghosts lie beyond the
// borrowed bodies. reach <= 0: d itself.
Decomposition with_overlap(const Model& model, const Decomposition& d, double reach);

// The local model of a submodel: own bodies, then borrowed ones, then ghosts; its joints,
// loads of own and borrowed bodies and drivers of local bodies, in global order, so that
// every own body's derivative is bit for bit the one of the whole model.
Model submodel_model(const Model& model, const Submodel& sub);

// The partitioned body/joint graph in Graphviz dot.
std::string decomposition_dot(const Model& model, const Decomposition& d);

}  // namespace mbsflow
