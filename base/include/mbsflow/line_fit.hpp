#pragma once
// Least-squares straight line y = intercept + slope * x through sample points: the one fit
// behind measured convergence orders, fitted scaling exponents (both on log-log data) and
// the Hockney model of a channel.
#include <cmath>
#include <cstddef>
#include <vector>

namespace mbsflow {

struct LineFit {
  double slope = 0;
  double intercept = 0;
};

inline LineFit line_fit(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const auto n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return {slope, (sy - slope * sx) / n};
}

// The exponent p of y ~ x^p: the slope of log y against log x.
inline double log_log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> lx, ly;
  for (std::size_t i = 0; i < x.size(); ++i) lx.push_back(std::log(x[i])), ly.push_back(std::log(y[i]));
  return line_fit(lx, ly).slope;
}

}  // namespace mbsflow
