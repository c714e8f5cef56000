#pragma once
// y'' = -y as a StepperSystem: with y(0) = 1, y'(0) = 0 the solution is (cos t, -sin t).
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow::test {

inline StepperSystem oscillator() {
  StepperSystem s;
  s.size = 2;
  s.rhs = [](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
    d.resize(2);
    d << y[1], -y[0];
  };
  return s;
}

}  // namespace mbsflow::test
