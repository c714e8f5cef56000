#pragma once
// Hairer & Wanner's starting step (I, II.4) for a method of order q, in the scaled max
// norm; shared by the implicit integrators.
#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {

double starting_step(const OdeProblem& p, const Eigen::VectorXd& y0, const Eigen::VectorXd& f0, const Eigen::VectorXd& scale,
                     int q, long& evaluations);

}  // namespace mbsflow
