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
  // A flexible body's frame, nodes and modes move as one: each of its bodies reads what
  // any of them reads. A rigid cluster's reactions come from one solve over the forces on
  // all its bodies, so each of its bodies reads whatever any of them reads. A body that
  // reads one of a flexible body's bodies reads all of them and its modes. Each rule may
  // widen what another joined: with flexible bodies, repeated until nothing changes.
  const Model& m = model();
  std::vector<std::vector<int>> group(m.flexible.size());
  for (std::size_t f = 0; f < m.flexible.size(); ++f) {
    group[f] = m.flexible[f].nodes;
    group[f].push_back(m.flexible[f].frame);
    std::sort(group[f].begin(), group[f].end());
  }
  auto sort_unique = [](std::vector<int>& r) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  };
  auto join = [&](const std::vector<int>& bodies) {
    std::vector<int> all;
    for (int b : bodies) all.insert(all.end(), reads[static_cast<std::size_t>(b)].begin(), reads[static_cast<std::size_t>(b)].end());
    sort_unique(all);
    bool changed = false;
    for (int b : bodies) {
      auto& r = reads[static_cast<std::size_t>(b)];
      sort_unique(r);
      changed = changed || r != all;
      r = all;
    }
    return changed;
  };
  auto reads_group = [&](std::size_t i, std::size_t f) {
    const auto& r = reads[i];
    return std::any_of(r.begin(), r.end(), [&](int b) { return compiled_->flexible_of_body[static_cast<std::size_t>(b)] == static_cast<int>(f); });
  };
  if (!m.flexible.empty())
    for (auto& r : reads) sort_unique(r);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t f = 0; f < m.flexible.size(); ++f) changed = join(group[f]) || changed;
    for (int c = 0; c < clusters(); ++c) changed = join(cluster_bodies(c)) || changed;
    if (m.flexible.empty()) break;
    for (std::size_t f = 0; f < m.flexible.size(); ++f)
      for (std::size_t i = 0; i < reads.size(); ++i)
        if (reads_group(i, f) && !std::includes(reads[i].begin(), reads[i].end(), group[f].begin(), group[f].end())) {
          reads[i].insert(reads[i].end(), group[f].begin(), group[f].end());
          sort_unique(reads[i]);
          changed = true;
        }
  }
  // Which bodies read flexible body f's modes, and what its modes' accelerations read (its
  // frame's reads: its whole group's).
  std::vector<std::vector<char>> reads_modes(m.flexible.size());
  std::vector<std::vector<int>> group_reads(m.flexible.size());
  for (std::size_t f = 0; f < m.flexible.size(); ++f) {
    reads_modes[f].assign(static_cast<std::size_t>(n), 0);
    for (Eigen::Index i = 0; i < n; ++i) reads_modes[f][static_cast<std::size_t>(i)] = reads_group(static_cast<std::size_t>(i), f);
    group_reads[f] = reads[static_cast<std::size_t>(m.flexible[f].frame)];
  }
  for (auto& r : reads) sort_unique(r);
  // Column by column (compressed, rows ascending), straight into the matrix: the model's
  // sizes make a list of triplets tens of megabytes. Rows of the velocity and angular
  // velocity of every body that reads body b: readers[b], ascending.
  std::vector<std::vector<int>> readers(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    for (int b : reads[static_cast<std::size_t>(i)]) readers[static_cast<std::size_t>(b)].push_back(static_cast<int>(i));
  const Eigen::Index size = layout_.size();
  Eigen::SparseMatrix<double> p(size, size);
  p.makeCompressed();
  // Two passes over the columns: the first counts each column's rows (the column starts),
  // the second writes them straight into the matrix, whose arrays (hundreds of MB on a
  // large model) are then made once and never copied.
  int* inner = nullptr;  // null while counting
  Eigen::Index at = 0, column = 0;
  auto push_rows = [&](Eigen::Index first, int count) {
    if (inner)
      for (int c = 0; c < count; ++c) inner[at + c] = static_cast<int>(first + c);
    at += count;
  };
  auto end_column = [&] {
    ++column;
    if (!inner) p.outerIndexPtr()[column] = static_cast<int>(at);
  };
  // A node's position and orientation rates follow its frame's orientation, velocity and
  // angular velocity and the modes (the dense output's node motion): those columns get the
  // nodes' rows too, each column's rows then sorted.
  std::vector<int> frame_of(m.flexible.empty() ? 0 : static_cast<std::size_t>(n), -1);
  for (std::size_t fl = 0; fl < m.flexible.size(); ++fl) frame_of[static_cast<std::size_t>(m.flexible[fl].frame)] = static_cast<int>(fl);
  auto push_node_rows = [&](std::size_t fl) {
    for (int node : m.flexible[fl].nodes) {
      push_rows(layout_.position(node), 3);
      push_rows(layout_.orientation(node), 4);
    }
    if (inner) std::sort(inner + p.outerIndexPtr()[column], inner + at);
  };
  enum Field { position, orientation, velocity, angular_velocity };
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      p.resizeNonZeros(at);
      inner = p.innerIndexPtr();
    }
    at = 0;
    column = 0;
    for (Field f : {position, orientation, velocity, angular_velocity}) {
      const int width = f == orientation ? 4 : 3;
      for (Eigen::Index b = 0; b < n; ++b)
        for (int k = 0; k < width; ++k) {
          if (f == velocity) push_rows(layout_.position(b), 3);  // r' = v
          if (f == orientation || f == angular_velocity) push_rows(layout_.orientation(b), 4);  // q' = q (x) (0, w) / 2
          for (const int i : readers[static_cast<std::size_t>(b)]) push_rows(layout_.velocity(i), 3);
          for (const int i : readers[static_cast<std::size_t>(b)]) push_rows(layout_.angular_velocity(i), 3);
          for (std::size_t fl = 0; fl < m.flexible.size(); ++fl)  // the modes' accelerations
            if (std::binary_search(group_reads[fl].begin(), group_reads[fl].end(), static_cast<int>(b)))
              push_rows(layout_.tail(compiled_->flexible_tail[fl]) + m.flexible[fl].data->modes(), m.flexible[fl].data->modes());
          if (f != position && !frame_of.empty() && frame_of[static_cast<std::size_t>(b)] >= 0)
            push_node_rows(static_cast<std::size_t>(frame_of[static_cast<std::size_t>(b)]));
          end_column();
        }
    }
    // The modal coordinates' and rates' columns: the rates of every body that reads the
    // flexible body, and the modes' own.
    for (std::size_t fl = 0; fl < m.flexible.size(); ++fl) {
      const int ne = m.flexible[fl].data->modes();
      const Eigen::Index tail = layout_.tail(compiled_->flexible_tail[fl]);
      for (int rate = 0; rate < 2; ++rate)
        for (int k = 0; k < ne; ++k) {
          for (Eigen::Index i = 0; i < n; ++i)
            if (reads_modes[fl][static_cast<std::size_t>(i)]) push_rows(layout_.velocity(i), 3);
          for (Eigen::Index i = 0; i < n; ++i)
            if (reads_modes[fl][static_cast<std::size_t>(i)]) push_rows(layout_.angular_velocity(i), 3);
          if (rate) push_rows(tail + k, 1);  // eta' = eta rate
          for (std::size_t g = 0; g < m.flexible.size(); ++g)  // the modal accelerations that read these modes
            if (reads_modes[fl][static_cast<std::size_t>(m.flexible[g].frame)])
              push_rows(layout_.tail(compiled_->flexible_tail[g]) + m.flexible[g].data->modes(), m.flexible[g].data->modes());
          push_node_rows(fl);  // sorts the column's rows
          end_column();
        }
    }
  }
  std::fill_n(p.valuePtr(), p.nonZeros(), 1.0);
  return p;
}

}  // namespace mbsflow
