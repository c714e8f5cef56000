#pragma once
// The stopping rule of the implicit iterations (Hairer & Wanner, IV.8), shared by the block
// methods and the triangularised Runge-Kutta methods: with the contraction rate theta from
// the last two corrections and eta = theta / (1 - theta), the iteration has converged when
// eta |dU| <= tol; it has failed when theta reaches 0.99, a correction is not finite, or
// the iteration count runs out. eta carries over to the next step's first iteration.
// With predict_failure (Radau5's rule) it fails as soon as the rate says that the
// remaining iterations cannot reach the tolerance: theta^(left) / (1 - theta) |dU| > tol.
#include <algorithm>
#include <cmath>

#include "mbsflow/methods/state_archive.hpp"
#include <limits>

namespace mbsflow {

// |du| within a few units of rounding of |u| (or of the smallest normal number).
template <class D, class U>
bool at_roundoff(const D& du, const U& u) {
  const double eps = std::numeric_limits<double>::epsilon();
  return (du.array().abs() <= 8 * eps * u.array().abs() + std::numeric_limits<double>::min()).all();
}

enum class IterationVerdict { iterate, converged, failed };

struct ConvergenceMonitor {
  double tol = 0.03;
  int max_iterations = 7;
  bool predict_failure = false;
  double eta = 1.0, last_norm = 0, theta = 0;

  // Checkpoints: eta carries over from step to step.
  void save(StateWriter& out) const {
    for (double v : {eta, last_norm, theta}) out.real(v);
  }
  void restore(StateReader& in) {
    for (double* v : {&eta, &last_norm, &theta}) *v = in.real();
  }

  // After correction number `iteration` (1, 2, ...) of scaled size `norm`; `at_roundoff`:
  // every correction was within rounding of its iterate, so it cannot get smaller.
  IterationVerdict next(int iteration, double norm, bool at_roundoff) {
    if (!std::isfinite(norm)) return IterationVerdict::failed;
    if (at_roundoff) return IterationVerdict::converged;
    double e;
    if (iteration == 1) {
      theta = 0;
      e = std::pow(std::max(eta, std::numeric_limits<double>::epsilon()), 0.8);
    } else {
      theta = norm / last_norm;
      // Corrections that stopped shrinking while both were already within the tolerance:
      // rounding noise (tight tolerances make it visible), not divergence.
      if (theta >= 0.99 && norm <= tol && last_norm <= tol) {
        eta = 1.0;
        return IterationVerdict::converged;
      }
      if (theta >= 0.99) return IterationVerdict::failed;
      e = theta / (1 - theta);
    }
    last_norm = norm;
    if (e * norm <= tol || norm == 0) {
      eta = e;
      return IterationVerdict::converged;
    }
    if (iteration >= max_iterations) return IterationVerdict::failed;
    if (predict_failure && iteration > 1 && std::pow(theta, max_iterations - iteration) * e * norm > tol)
      return IterationVerdict::failed;
    return IterationVerdict::iterate;
  }
};

}  // namespace mbsflow
