#pragma once
#include <optional>
#include <vector>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {
// METIS k-way assignment of bodies to parts, or nothing if METIS cannot give k non-empty parts.
std::optional<std::vector<int>> metis_partition(const Model& m, const std::vector<double>& cost, int k);
}  // namespace mbsflow
