// The numerical A-stability check behind StabilityReport.
#include "mbsflow/methods/stability.hpp"

#include "mbsflow/methods/real_eigen.hpp"
#include <cmath>
#include <limits>

namespace mbsflow {

StabilityReport stability_report(const std::function<std::complex<double>(std::complex<double>)>& r,
                                 const Eigen::MatrixXd& implicit, double at_infinity) {
  StabilityReport rep;
  rep.at_infinity = at_infinity;
  rep.min_pole_real_part = std::numeric_limits<double>::infinity();
  const Eigen::VectorXcd mu = eigenvalues_of(implicit);
  for (Eigen::Index i = 0; i < mu.size(); ++i)
    if (std::abs(mu(i)) > 1e-14) rep.min_pole_real_part = std::min(rep.min_pole_real_part, (1.0 / mu(i)).real());
  for (int k = 0; k <= 4000; ++k) {
    const double y = k == 0 ? 0.0 : std::pow(10.0, -3.0 + 7.0 * (k - 1) / 3999.0);
    rep.max_on_imaginary_axis = std::max(rep.max_on_imaginary_axis, std::abs(r({0.0, y})));
  }
  const double slack = 1e-12;
  rep.a_stable = rep.min_pole_real_part > 0 && rep.max_on_imaginary_axis <= 1 + slack && rep.at_infinity <= 1 + slack;
  return rep;
}

const char* stability_verdict(const StabilityReport& r) {
  return r.l_stable() ? "L-stable" : r.a_stable ? "A-stable, not L-stable (stiff components are not damped)" : "not A-stable";
}

}  // namespace mbsflow
