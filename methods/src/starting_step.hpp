#pragma once
// Hairer & Wanner's starting step (I, II.4) for a method of order q, in the weighted RMS
// norm, and the smallest step; shared by the implicit integrators.
#include <algorithm>
#include <cmath>
#include <limits>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

double starting_step(const OdeProblem& p, const Eigen::VectorXd& y0, const Eigen::VectorXd& f0, const Eigen::VectorXd& scale,
                     int q, long& evaluations);

// The smallest step the integrators take at time t: below 10 eps |t| a step no longer
// moves t reliably (Radau5's limit). Not bounded below by a time scale of its own: an initial
// layer of 1e-13 at t = 0 (Van der Pol with mu = 1e6) needs steps of 1e-15 there.
inline double smallest_step(double t) {
  return std::max(10 * std::numeric_limits<double>::epsilon() * std::abs(t), std::numeric_limits<double>::min());
}

// Whether step tau at t is below the smallest step (the settings' min_step, or 0 for
// smallest_step(t)): null if not, else what to add to the failure message (why a step below
// smallest_step cannot be taken; nothing for the user's own minimum).
inline const char* step_underflow(double tau, double t, double min_step) {
  if (tau >= (min_step > 0 ? min_step : smallest_step(t))) return nullptr;
  return min_step > 0 ? ""
                      : ": below 10 eps |t| a step no longer moves t reliably; the solution changes here faster than this method "
                        "can follow at this tolerance in double precision (loosen the tolerance, or use a method of higher order)";
}

}  // namespace mbsflow
