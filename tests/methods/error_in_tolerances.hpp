#pragma once
// An error in units of the tolerance, as Radau5 and CVODE weigh it:
// max_i |y_i - ref_i| / (atol_i + rtol |ref_i|).
#include <Eigen/Core>

namespace mbsflow::test {

inline double error_in_tolerances(const Eigen::VectorXd& y, const Eigen::VectorXd& reference, double rtol, const Eigen::ArrayXd& atol) {
  return ((y - reference).array().abs() / (atol + rtol * reference.array().abs())).maxCoeff();
}

}  // namespace mbsflow::test
