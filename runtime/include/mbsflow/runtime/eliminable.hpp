#pragma once
// A multibody state's positions and quaternions as the blocks the implicit methods' sparse
// Newton solvers eliminate first (OdeProblem::eliminable, StepperSystem::eliminable).
#include <vector>

#include "mbsflow/graph/state_layout.hpp"
#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

// Per body its position and its quaternion: their rates read only the same body's state
// (r' = v, q' = q (x) (0, w) / 2).
inline std::vector<RowRange> eliminable_unknowns(const StateLayout& layout) {
  std::vector<RowRange> out;
  out.reserve(static_cast<std::size_t>(2 * layout.bodies));
  for (Eigen::Index i = 0; i < layout.bodies; ++i) out.push_back({layout.position(i), layout.position(i) + 3});
  for (Eigen::Index i = 0; i < layout.bodies; ++i) out.push_back({layout.orientation(i), layout.orientation(i) + 4});
  return out;
}

}  // namespace mbsflow
