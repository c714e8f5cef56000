#pragma once
// The state of one submodel in a partitioned RK4 run and the work of one of its stages.
#include <vector>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "step_grid.hpp"

namespace mbsflow::partitioned {

struct Part {
  Part(const Model& model, const Submodel& sub);
  const Submodel* sub;
  MultibodySystem system;  // the local model: own bodies first, then ghosts
  Eigen::Index own = 0;    // own body count
  // x[0] is the state y; x[1..3] the stage inputs. k[s] the stage derivatives.
  Eigen::VectorXd x[4], k[4];
};

// Copies the ghost bodies' values of stage input s from their owners.
void pull_ghosts(std::vector<Part>& parts, std::size_t p, int s);
// Stage s of the step from t to t_next: k_s = f(x_s); then x_{s+1} = y + c h k_s for own
// bodies, or after stage 3 the new y for own bodies (renormalised, drivers imposed).
// h = t_next - t and the times are those of the sequential loop, to the bit.
void stage(Part& part, int s, double t, double t_next);
// Own bodies' states into the global state vector (global body order).
void gather(const std::vector<Part>& parts, const StateLayout& global, Eigen::VectorXd& y);
std::optional<Divergence> check(const std::vector<Part>& parts);  // body index is global

}  // namespace mbsflow::partitioned
