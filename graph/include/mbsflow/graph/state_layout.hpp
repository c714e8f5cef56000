#pragma once
// Where each body's numbers sit in the state vector. Structure of arrays by field:
// all positions (3 per body), then all quaternions (4), velocities (3), angular velocities (3).
#include <Eigen/Core>
#include <algorithm>

namespace mbsflow {

struct StateLayout {
  Eigen::Index bodies = 0;
  // After the bodies' fields: the flexible bodies' modal coordinates and their rates
  // (flexible_body.hpp), `extra` numbers in all.
  Eigen::Index extra = 0;
  Eigen::Index size() const { return 13 * bodies + extra; }
  Eigen::Index tail(Eigen::Index k) const { return 13 * bodies + k; }
  Eigen::Index position(Eigen::Index i) const { return 3 * i; }
  Eigen::Index orientation(Eigen::Index i) const { return 3 * bodies + 4 * i; }
  Eigen::Index velocity(Eigen::Index i) const { return 7 * bodies + 3 * i; }
  Eigen::Index angular_velocity(Eigen::Index i) const { return 10 * bodies + 3 * i; }
};

// Calls f(first, count) for each run of consecutive bodies in list[0..n) (0..n-1, one run,
// when list is null): the layout keeps each field of consecutive bodies together, so a
// run's numbers of one field are one block.
template <class F>
void for_body_runs(const int* list, std::size_t n, F&& f) {
  for (std::size_t a = 0; a < n;) {
    std::size_t b = list ? a + 1 : n;
    while (b < n && list[b] == list[b - 1] + 1) ++b;
    f(static_cast<Eigen::Index>(list ? list[a] : static_cast<int>(a)), static_cast<Eigen::Index>(b - a));
    a = b;
  }
}

// The state's field blocks in order (position, orientation, velocity, angular velocity):
// each one's offset in a layout and its numbers per body.
struct StateField {
  Eigen::Index (StateLayout::*offset)(Eigen::Index) const;
  int width;
};
inline constexpr StateField state_fields[4] = {
    {&StateLayout::position, 3}, {&StateLayout::orientation, 4}, {&StateLayout::velocity, 3}, {&StateLayout::angular_velocity, 3}};

// Largest distance between the centres of mass of the same body in two states.
inline double largest_position_gap(const StateLayout& l, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  double gap = 0.0;
  for (Eigen::Index i = 0; i < l.bodies; ++i)
    gap = std::max(gap, (a.segment<3>(l.position(i)) - b.segment<3>(l.position(i))).norm());
  return gap;
}

}  // namespace mbsflow
