#include "starting_step.hpp"

#include "error_norm.hpp"

#include <algorithm>
#include <cmath>

namespace mbsflow {

// Hairer & Wanner's starting step (I, II.4) for a method of order q, with the block's
// weighted RMS norm (error_norm.hpp).
double starting_step(const OdeProblem& p, const Eigen::VectorXd& y0, const Eigen::VectorXd& f0, const Eigen::VectorXd& scale,
                     int q, long& evaluations) {
  const double d0 = weighted_rms(y0, scale), d1 = weighted_rms(f0, scale);
  const double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  Eigen::VectorXd y1 = y0 + h0 * f0, f1(p.size);
  p.evaluate(p.t0 + h0, y1, f1);
  ++evaluations;
  const double d2 = weighted_rms(f1 - f0, scale) / h0, dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / (q + 1));
  return std::min(100 * h0, h1);
}

}  // namespace mbsflow
