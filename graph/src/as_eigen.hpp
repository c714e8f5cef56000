#pragma once
// A model's 3-vectors and quaternions (std::array) as Eigen vectors.
#include <Eigen/Core>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

inline Eigen::Vector3d vec(const Vec3& v) { return {v[0], v[1], v[2]}; }
inline Eigen::Vector4d vec(const Quat& q) { return {q[0], q[1], q[2], q[3]}; }

}  // namespace mbsflow
