#pragma once
// Where each body's numbers sit in the state vector. Structure of arrays by field:
// all positions (3 per body), then all quaternions (4), velocities (3), angular velocities (3).
#include <Eigen/Core>

namespace mbsflow {

struct StateLayout {
  Eigen::Index bodies = 0;
  Eigen::Index size() const { return 13 * bodies; }
  Eigen::Index position(Eigen::Index i) const { return 3 * i; }
  Eigen::Index orientation(Eigen::Index i) const { return 3 * bodies + 4 * i; }
  Eigen::Index velocity(Eigen::Index i) const { return 7 * bodies + 3 * i; }
  Eigen::Index angular_velocity(Eigen::Index i) const { return 10 * bodies + 3 * i; }
};

}  // namespace mbsflow
