#pragma once
// A model's 3-vector (std::array) as an Eigen vector.
#include <Eigen/Core>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

inline Eigen::Vector3d vec(const Vec3& v) { return {v[0], v[1], v[2]}; }

}  // namespace mbsflow
