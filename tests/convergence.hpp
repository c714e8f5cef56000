#pragma once
// Measured order of convergence.
#include <cmath>
#include <vector>

#include "mbsflow/line_fit.hpp"

namespace mbsflow::test {

// Least-squares slope of log(err) against log(h).
inline double convergence_slope(const std::vector<double>& h, const std::vector<double>& err) {
  std::vector<double> x, y;
  for (std::size_t i = 0; i < h.size(); ++i) x.push_back(std::log(h[i])), y.push_back(std::log(err[i]));
  return line_fit(x, y).slope;
}

}  // namespace mbsflow::test
