#pragma once
// The warning both ODE front ends (mbsflow ode, Python's solve_ivp) give when a component's
// size stayed below its absolute tolerance at every point the solver returned: it is held
// to atol in absolute terms only, none of its digits need be right, and a solution that
// depends on it can end far off (Robertson's 1e-5 component under atol = 1e-4, the test
// set's E5 under any scalar atol). The text names the setting in braces ({atol=...}); each
// front end renders it (error.hpp's render).
#include <Eigen/Core>
#include <functional>
#include <string>

namespace mbsflow {

// largest: per component, the largest |y| over the returned points; atol, or atols where
// given per component; name(i): how the front end calls component i; where: the points, as
// "at any accepted step". Empty where every component grew past its tolerance.
std::string uncontrolled_warning(const Eigen::VectorXd& largest, double atol, const Eigen::VectorXd& atols,
                                 const std::function<std::string(Eigen::Index)>& name, const std::string& where);

}  // namespace mbsflow
