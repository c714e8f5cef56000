// The sparsity pattern of the multibody right-hand side's Jacobian, from the body graph.
#include <algorithm>
#include <vector>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

Eigen::SparseMatrix<double> MultibodySystem::jacobian_pattern() const {
  const Eigen::Index n = layout_.bodies;
  // Per body, the bodies whose states its accelerations read (itself included); the
  // lists are sorted and made unique below.
  std::vector<std::vector<int>> reads(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) reads[static_cast<std::size_t>(i)].push_back(static_cast<int>(i));
  auto couple = [&](const std::vector<int>& bodies) {
    for (int a : bodies)
      if (a >= 0 && a < n)
        for (int b : bodies)
          if (b >= 0 && b < n) reads[static_cast<std::size_t>(a)].push_back(b);
  };
  for (const Joint& j : model_.joints) couple({j.body1, j.body2});
  for (const auto& e : elements_) couple(e->bodies());
  // A rigid cluster's reactions come from one solve over the forces on all its bodies, so
  // each of its bodies reads whatever any of them reads.
  for (int c = 0; c < clusters(); ++c) {
    std::vector<int> all;
    for (int b : cluster_bodies(c)) all.insert(all.end(), reads[static_cast<std::size_t>(b)].begin(), reads[static_cast<std::size_t>(b)].end());
    for (int b : cluster_bodies(c)) reads[static_cast<std::size_t>(b)] = all;
  }

  std::vector<Eigen::Triplet<double>> t;
  auto block = [&](Eigen::Index row, int rows, Eigen::Index col, int cols) {
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) t.emplace_back(row + r, col + c, 1.0);
  };
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<int>& r = reads[static_cast<std::size_t>(i)];
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    // r' = v; q' = q (x) (0, w) / 2.
    block(layout_.position(i), 3, layout_.velocity(i), 3);
    block(layout_.orientation(i), 4, layout_.orientation(i), 4);
    block(layout_.orientation(i), 4, layout_.angular_velocity(i), 3);
    for (int b : r)
      for (Eigen::Index row : {layout_.velocity(i), layout_.angular_velocity(i)}) {
        block(row, 3, layout_.position(b), 3);
        block(row, 3, layout_.orientation(b), 4);
        block(row, 3, layout_.velocity(b), 3);
        block(row, 3, layout_.angular_velocity(b), 3);
      }
  }
  Eigen::SparseMatrix<double> p(layout_.size(), layout_.size());
  p.setFromTriplets(t.begin(), t.end(), [](double, double) { return 1.0; });
  p.makeCompressed();
  return p;
}

}  // namespace mbsflow
