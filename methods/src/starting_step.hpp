#pragma once
// Hairer & Wanner's starting step (I, II.4) for a method of order q, in the scaled max
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

// What a step size underflow at smallest_step means, for the failure message.
inline constexpr const char* step_underflow_hint =
    ": below 10 eps |t| a step no longer moves t reliably; the solution changes here faster than this method can follow "
    "at this tolerance in double precision (loosen the tolerance, or use a method of higher order)";

}  // namespace mbsflow
