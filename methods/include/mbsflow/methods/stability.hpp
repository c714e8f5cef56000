#pragma once
// Linear stability of a one-step method, from its stability function R (y' = lambda y,
// z = lambda tau: y_1 = R(z) y_0), shared by the block methods and the Runge-Kutta
// tableaux: A-stability checked numerically and the value at infinity, which says
// whether stiff components are damped (L-stability: A-stable with R(infinity) = 0).
#include <Eigen/Core>
#include <complex>
#include <functional>

namespace mbsflow {

// A-stable: no pole of R in the closed left half-plane, |R(iy)| <= 1 on a logarithmic
// grid of the imaginary axis, and |R(infinity)| <= 1.
struct StabilityReport {
  bool a_stable = false;
  double max_on_imaginary_axis = 0;  // max |R(iy)| over the grid
  double at_infinity = 0;
  double min_pole_real_part = 0;  // smallest Re of the poles (must be > 0)
  bool l_stable() const { return a_stable && at_infinity < 1e-12; }
};

// implicit: the method's implicit matrix (A of a tableau, g of a block), whose nonzero
// eigenvalues mu give the poles 1/mu of R.
StabilityReport stability_report(const std::function<std::complex<double>(std::complex<double>)>& r,
                                 const Eigen::MatrixXd& implicit, double at_infinity);
// "L-stable", "A-stable, not L-stable (...)" or "not A-stable", for --describe.
const char* stability_verdict(const StabilityReport& r);

}  // namespace mbsflow
