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
  for (const CompiledJoint& j : compiled_->joints) couple({j.a, j.b});  // ground is n: no state
  for (const auto& e : compiled_->elements) couple(e->bodies());
  // A rigid cluster's reactions come from one solve over the forces on all its bodies, so
  // each of its bodies reads whatever any of them reads.
  for (int c = 0; c < clusters(); ++c) {
    std::vector<int> all;
    for (int b : cluster_bodies(c)) all.insert(all.end(), reads[static_cast<std::size_t>(b)].begin(), reads[static_cast<std::size_t>(b)].end());
    for (int b : cluster_bodies(c)) reads[static_cast<std::size_t>(b)] = all;
  }

  for (auto& r : reads) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  // Column by column (compressed, rows ascending), straight into the matrix: the model's
  // sizes make a list of triplets tens of megabytes. Rows of the velocity and angular
  // velocity of every body that reads body b: readers[b], ascending.
  std::vector<std::vector<int>> readers(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    for (int b : reads[static_cast<std::size_t>(i)]) readers[static_cast<std::size_t>(b)].push_back(static_cast<int>(i));
  const Eigen::Index size = layout_.size();
  Eigen::SparseMatrix<double> p(size, size);
  p.makeCompressed();
  std::vector<int> inner;
  std::vector<int> outer{0};
  outer.reserve(static_cast<std::size_t>(size) + 1);
  auto push_rows = [&](Eigen::Index first, int count) {
    for (int c = 0; c < count; ++c) inner.push_back(static_cast<int>(first + c));
  };
  enum Field { position, orientation, velocity, angular_velocity };
  for (Field f : {position, orientation, velocity, angular_velocity}) {
    const int width = f == orientation ? 4 : 3;
    for (Eigen::Index b = 0; b < n; ++b)
      for (int k = 0; k < width; ++k) {
        if (f == velocity) push_rows(layout_.position(b), 3);  // r' = v
        if (f == orientation || f == angular_velocity) push_rows(layout_.orientation(b), 4);  // q' = q (x) (0, w) / 2
        for (const int i : readers[static_cast<std::size_t>(b)]) push_rows(layout_.velocity(i), 3);
        for (const int i : readers[static_cast<std::size_t>(b)]) push_rows(layout_.angular_velocity(i), 3);
        outer.push_back(static_cast<int>(inner.size()));
      }
  }
  p.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), p.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), p.innerIndexPtr());
  std::fill_n(p.valuePtr(), inner.size(), 1.0);
  return p;
}

}  // namespace mbsflow
