#pragma once
// A flexible body's coordinates as one evaluation reads them from the state: shared by
// its own rates (flexible_system.cpp) and the rigid joints at it (flexible_joints.cpp).
#include <Eigen/Core>

#include "mbsflow/graph/flexible_body.hpp"
#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow {

// The frame's body index, the modal coordinates and rates, and the frame's angular
// velocity (body axes) at y.
struct FlexibleAt {
  const FloatingFrameData& d;
  int ne, frame;
  Eigen::Index tail;
  Eigen::VectorXd eta, eta_rate;
  Eigen::Vector3d w;
};

inline FlexibleAt flexible_at(const FlexibleBody& fb, const StateLayout& l, Eigen::Index offset, const Eigen::VectorXd& y) {
  const int ne = fb.data->modes();
  const Eigen::Index tail = l.tail(offset);
  return {*fb.data, ne, fb.frame, tail, y.segment(tail, ne), y.segment(tail + ne, ne), y.segment<3>(l.angular_velocity(fb.frame))};
}

}  // namespace mbsflow
