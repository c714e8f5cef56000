#pragma once
// The state of one submodel in a partitioned run and the work of one of its stages, for
// RK4 and DOPRI5. Own bodies are computed here; ghosts are pulled from their owners.
#include <memory>
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/runtime/divergence.hpp"

namespace mbsflow::partitioned {

struct Part {
  // rk4_folded (taken for RK4's 4 stages on a submodel with no borrowed bodies): three
  // state vectors and two derivatives instead of four each (input() and derivative()
  // below), 3 x 104 bytes per body less.
  // The system is built from a copy of the submodel's part of the model, and then keeps
  // only the copy's bodies, loads and drivers: the joints' records (names, parameters,
  // 256 bytes each) have been compiled, and nothing reads them afterwards.
  Part(const Model& model, const Submodel& sub, int stages, bool rk4_folded = false);
  const Submodel* sub;
  MultibodySystem system;  // the local model: own bodies first, then ghosts
  Eigen::Index own = 0;    // own body count
  // x[0] is the state y, x[s] the input of stage s; k[s] the stage derivatives;
  // r the DOPRI5 dense-output coefficients of the last accepted step.
  std::vector<Eigen::VectorXd> x, k, r;
  // With rk4_folded, stage inputs 1 and 3 share x[1]: a neighbour takes stage input 1's
  // values before its stage 1, and this part writes input 3 in its stage 2, which waits
  // for that neighbour's stage 1 (a cut joint makes both sides each other's neighbours; the
  // inner half of stage 2 writes no body a neighbour takes). k2, k3 and k4 share k[1]: k[0]
  // holds k1, and then the sum of those taken so far (rk4::accumulate). Only a body's own
  // stage update reads its derivative, so the halves of two stages, which write other
  // bodies, never meet in one.
  bool rk4_folded = false;
  Eigen::VectorXd& input(int s) { return x[slot(s)]; }
  const Eigen::VectorXd& input(int s) const { return x[slot(s)]; }
  Eigen::VectorXd& derivative(int s) { return k[derivative_slot(s)]; }
  const Eigen::VectorXd& derivative(int s) const { return k[derivative_slot(s)]; }
  std::size_t slot(int s) const { return rk4_folded && s == 3 ? 1 : static_cast<std::size_t>(s); }
  std::size_t derivative_slot(int s) const { return rk4_folded ? (s == 0 ? 0 : 1) : static_cast<std::size_t>(s); }
  // For a stage in two halves (rk4_inner_stage, rk4_edge_stage): own bodies with no joint
  // to a ghost (inner) and with one (edge), the ghosts, and the local joints that reach
  // no ghost and that do.
  std::vector<int> own_bodies, inner_bodies, edge_bodies, ghost_bodies, inner_joints, ghost_joints;
  // The whole model's state layout, and the flexible bodies held here: where their modal
  // coordinates and rates (2 ne numbers) sit locally and in the whole state, and their
  // frame's local index (a stage half that takes the frame takes them).
  StateLayout global;
  struct Tail {
    Eigen::Index local = 0, global = 0, size = 0;
    int frame = 0;
  };
  std::vector<Tail> tails;

 private:
  Part(std::shared_ptr<Model> local, const Submodel& sub, int stages, bool rk4_folded);
};

// Copies the ghost bodies' values of stage input s of parts[p] from their owners in this
// process (parts[q] null: q runs elsewhere).
void copy_local_ghosts(const std::vector<Part*>& parts, std::size_t p, int s);
// The same for one exchange, from an owner in this process, or from an owner's state
// vector `from` (in its layout) kept from earlier.
void copy_ghosts(const Part& owner, const Submodel::Exchange& e, Part& me, int s);
void copy_ghosts(const StateLayout& owner_layout, const Eigen::VectorXd& from, const Submodel::Exchange& e, Part& me, int s);

// Bodies' values as 13 numbers each (position, orientation, velocity, angular velocity),
// for another process or the coordinator, and back. Bit for bit; the buffer need not be
// aligned for doubles (a message's often is not).
constexpr int body_numbers = 13;
void pack_bodies(const StateLayout& l, const Eigen::VectorXd& x, const std::vector<int>& bodies, void* out);
void unpack_bodies(const StateLayout& l, Eigen::VectorXd& x, const std::vector<int>& bodies, const void* in);

// A worker's share of the whole state, in the order it sends it to the coordinator: its
// submodels' own bodies (13 numbers each, as pack_bodies), then their flexible bodies'
// modal coordinates and rates.
struct StateShare {
  std::vector<int> bodies;  // global indices
  struct Span {
    Eigen::Index at = 0, size = 0;  // in the whole state
  };
  std::vector<Span> tails;
  void add(const Decomposition& d, const Submodel& s);  // s's own bodies and flexible bodies
  std::size_t numbers() const;
};
void pack_share(const StateLayout& global, const Eigen::VectorXd& y, const StateShare& share, void* out);
void unpack_share(const StateLayout& global, Eigen::VectorXd& y, const StateShare& share, const void* in);

// The places in the whole state of submodel q's own entries: field block by field block
// (bodies in order within each), then its flexible bodies' tails.
std::vector<Eigen::Index> own_elements(const Decomposition& d, std::size_t q);

// Calls f(offset, length) for the own entries of each field block of the local state,
// then for each flexible body's tail.
template <class F>
void for_own_blocks(const Part& part, F f) {
  for (const StateField& field : state_fields) f((part.system.layout().*field.offset)(0), field.width * part.own);
  for (const Part::Tail& t : part.tails) f(t.local, t.size);
}

// RK4 stage s of the step from t to t_next: k_s = f(x_s); then x_{s+1} = y + c h k_s for
// own bodies, or after stage 3 the new y for own bodies (renormalised, drivers imposed).
// h = t_next - t and the times are those of the sequential loop, to the bit.
void rk4_stage(Part& part, int s, double t, double t_next);

// rk4_stage in two halves with the same numbers: the inner half needs no ghost values
// (run it while they travel), the edge half needs the ghosts of stage input s and makes
// the values the neighbours need next.
void rk4_inner_stage(Part& part, int s, double t, double t_next);
void rk4_edge_stage(Part& part, int s, double t, double t_next);

// DOPRI5 stage s (0..6) of an attempt of step h from t: k_s = f(x_s) (k_0 only if
// need_k0), then x_{s+1} for own bodies; after stage 6 the squared scaled errors of own
// elements go to their global places in squares.
void dopri5_stage(Part& part, int s, double t, double h, bool need_k0, double atol, double rtol,
                  Eigen::VectorXd& squares);
// After an accepted DOPRI5 step to t_new: dense coefficients, y = x_6, renormalise.
void dopri5_accept(Part& part, double h, double t_new);
// Own bodies' dense output at fraction theta of the last accepted step, into out (global).
void dopri5_dense(const Part& part, double theta, Eigen::VectorXd& out);

// Own bodies' states (x[0]) into the global state vector (sized by the first form).
void gather(const std::vector<Part>& parts, const StateLayout& global, Eigen::VectorXd& y);
void gather(const Part& part, const StateLayout& global, Eigen::VectorXd& y);
void gather(const Part& part, const Eigen::VectorXd& local, const StateLayout& global, Eigen::VectorXd& y);  // from `local`
// The reverse (a resumed run): every local body's state (own, borrowed, ghosts) from the
// global state into x[0], as at the start, where each process has the whole state.
void scatter(const Eigen::VectorXd& y, const StateLayout& global, Part& part);
std::optional<Divergence> check(const std::vector<Part>& parts);  // body index is global
std::optional<Divergence> check(const Part& part);

}  // namespace mbsflow::partitioned
