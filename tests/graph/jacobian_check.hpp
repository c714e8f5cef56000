#pragma once
// The Jacobian tests' yardsticks: a shaken state of a multibody system, central
// differences of its right-hand side, and the largest difference between two Jacobians.
#include <Eigen/Geometry>
#include <algorithm>
#include <random>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow::test {

// A state away from rest: random displacements, large rotations (up to ~1 rad, so the
// bushings' rotation logarithm runs outside its series), velocities, spin, deformation.
inline Eigen::VectorXd shaken_state(MultibodySystem& sys, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd y = sys.initial_state();
  const StateLayout& l = sys.layout();
  for (Eigen::Index i = 0; i < l.bodies; ++i) {
    for (int k = 0; k < 3; ++k) {
      y[l.position(i) + k] += 0.05 * u(rng);
      y[l.velocity(i) + k] = 0.5 * u(rng);
      y[l.angular_velocity(i) + k] = 3.0 * u(rng);
    }
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.6 * (1 + u(rng)) / 2 + 0.1 * i, axis));
    y.segment<4>(l.orientation(i)) = 1.01 * Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());  // not unit: the rhs normalises
  }
  for (Eigen::Index k = 0; k < l.extra; ++k) y[l.tail(0) + k] += 0.02 * u(rng);  // flexible bodies' modes and their rates
  sys.after_step(0.0, y);  // puts the driven body on its motion, the flexible bodies' nodes on theirs
  return y;
}

// Central differences, column by column, into a dense matrix.
inline Eigen::MatrixXd central_differences(MultibodySystem& sys, double t, const Eigen::VectorXd& y) {
  const Eigen::Index n = sys.dimension();
  Eigen::MatrixXd j(n, n);
  Eigen::VectorXd fp(n), fm(n);
  for (Eigen::Index c = 0; c < n; ++c) {
    const double h = 1e-6 * std::max(1.0, std::abs(y[c]));
    Eigen::VectorXd yp = y, ym = y;
    yp[c] += h;
    ym[c] -= h;
    sys.rhs(t, yp, fp);
    sys.rhs(t, ym, fm);
    j.col(c) = (fp - fm) / (2 * h);
  }
  return j;
}

// The largest difference of exact from fd, entry by entry, relative to the largest entry
// of fd's row (at least 1: rows mix 1 and 1e5).
inline double largest_row_difference(const Eigen::MatrixXd& exact, const Eigen::MatrixXd& fd) {
  double worst = 0;
  for (Eigen::Index r = 0; r < exact.rows(); ++r) {
    const double scale = std::max(1.0, fd.row(r).cwiseAbs().maxCoeff());
    worst = std::max(worst, (exact.row(r) - fd.row(r)).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

}  // namespace mbsflow::test
