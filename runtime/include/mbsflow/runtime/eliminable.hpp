#pragma once
// A multibody state's positions and quaternions as the blocks the implicit methods' sparse
// Newton solvers eliminate first (OdeProblem::eliminable, StepperSystem::eliminable).
#include <vector>

#include "mbsflow/graph/state_layout.hpp"
#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

inline std::vector<RowRange> eliminable_unknowns(const StateLayout& layout) {
  std::vector<RowRange> out;
  for (const auto& [first, count] : kinematic_blocks(layout)) out.push_back({first, first + count});
  return out;
}

}  // namespace mbsflow
