#pragma once
// Cubic Hermite interpolation between two points with their derivatives (third order): the
// dense output of the steppers that keep no interpolant of their own.
#include <Eigen/Core>

namespace mbsflow {

inline void cubic_hermite(double t0, const Eigen::VectorXd& y0, const Eigen::VectorXd& f0, double t1, const Eigen::VectorXd& y1,
                          const Eigen::VectorXd& f1, double t, Eigen::VectorXd& out) {
  const double h = t1 - t0, th = h > 0 ? (t - t0) / h : 1.0, th1 = th - 1.0;
  const double h00 = (1 + 2 * th) * th1 * th1, h10 = th * th1 * th1, h01 = th * th * (3 - 2 * th), h11 = th * th * th1;
  out = h00 * y0 + (h10 * h) * f0 + h01 * y1 + (h11 * h) * f1;
}

}  // namespace mbsflow
