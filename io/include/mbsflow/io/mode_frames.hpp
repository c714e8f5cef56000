#pragma once
// A mode drawn as motion: the bodies at the equilibrium moved by a Re(shape e^(i phase)),
// a scaled so that the mode's largest body translation is a twentieth of the model's size
// (a mode of rotations only: its largest rotation a fifth of a radian). The XDMF sidecar
// of a modes file and mbsflow view draw modes this way.
#include <Eigen/Geometry>
#include <algorithm>
#include <complex>
#include <vector>

namespace mbsflow {

// The diagonal of the bounding box of `positions` (x, y, z per body); 1 m for one body.
inline double model_size(const std::vector<double>& positions) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
  for (std::size_t b = 0; b + 2 < positions.size(); b += 3) {
    const Eigen::Vector3d x(positions[b], positions[b + 1], positions[b + 2]);
    low = low.cwiseMin(x);
    high = high.cwiseMax(x);
  }
  const double d = positions.size() >= 3 ? (high - low).norm() : 0.0;
  return d > 0.0 ? d : 1.0;
}

// The factor a for one mode; shape(b, e) gives body b's coordinate e (0-2 translation,
// 3-5 rotation) of the mode, for b < bodies.
template <class Shape>
double mode_scale(Shape&& shape, std::size_t bodies, double size) {
  double largest_t = 0.0, largest_r = 0.0;
  for (std::size_t b = 0; b < bodies; ++b) {
    double t = 0.0, r = 0.0;
    for (int e = 0; e < 3; ++e) {
      t += std::norm(std::complex<double>(shape(b, e)));
      r += std::norm(std::complex<double>(shape(b, e + 3)));
    }
    largest_t = std::max(largest_t, std::sqrt(t));
    largest_r = std::max(largest_r, std::sqrt(r));
  }
  if (largest_t > 1e-12 * largest_r) return 0.05 * size / largest_t;
  return largest_r > 0.0 ? 0.2 / largest_r : 0.0;
}

// Body b of the mode at `phase`: its position (3) and orientation (w, x, y, z) from the
// equilibrium's.
template <class Shape>
void mode_frame_body(Shape&& shape, std::size_t b, double scale, double phase, const double* rest_position,
                     const double* rest_orientation, double* position, double* orientation) {
  const std::complex<double> turn(std::cos(phase), std::sin(phase));
  Eigen::Vector3d r;
  for (int i = 0; i < 3; ++i) {
    position[i] = rest_position[i] + scale * (std::complex<double>(shape(b, i)) * turn).real();
    r[i] = scale * (std::complex<double>(shape(b, i + 3)) * turn).real();
  }
  Eigen::Quaterniond q(rest_orientation[0], rest_orientation[1], rest_orientation[2], rest_orientation[3]);
  if (r.norm() > 0.0) q = Eigen::Quaterniond(Eigen::AngleAxisd(r.norm(), r.normalized())) * q;
  q.normalize();
  orientation[0] = q.w();
  orientation[1] = q.x();
  orientation[2] = q.y();
  orientation[3] = q.z();
}

}  // namespace mbsflow
