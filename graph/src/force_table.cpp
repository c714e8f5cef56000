#include "mbsflow/graph/force_table.hpp"

#include <algorithm>
#include <cmath>

namespace mbsflow {
namespace {

// Index of the segment [x_i, x_{i+1}] used for x (first or last beyond the ends).
std::size_t segment(const ForceTable& t, double x) {
  const auto& d = t.deflection;
  const auto it = std::upper_bound(d.begin() + 1, d.end() - 1, x);
  return static_cast<std::size_t>(it - d.begin()) - 1;
}

double slope(const ForceTable& t, std::size_t i) {
  return (t.force[i + 1] - t.force[i]) / (t.deflection[i + 1] - t.deflection[i]);
}

// Integral of the force from a to b with both in segment i's linear extension.
double segment_integral(const ForceTable& t, std::size_t i, double a, double b) {
  const double fa = t.force[i] + slope(t, i) * (a - t.deflection[i]);
  const double fb = t.force[i] + slope(t, i) * (b - t.deflection[i]);
  return 0.5 * (fa + fb) * (b - a);
}

}  // namespace

double table_force(const ForceTable& t, double x) {
  if (t.deflection.size() < 2) return 0.0;
  const std::size_t i = segment(t, x);
  return t.force[i] + slope(t, i) * (x - t.deflection[i]);
}

double table_slope(const ForceTable& t, double x) {
  if (t.deflection.size() < 2) return 0.0;
  return slope(t, segment(t, x));
}

double table_energy(const ForceTable& t, double x) {
  if (t.deflection.size() < 2) return 0.0;
  const double lo = std::min(0.0, x), hi = std::max(0.0, x);
  double sum = 0.0;
  double a = lo;
  while (a < hi) {
    const std::size_t i = segment(t, a);
    // Move to the end of this segment (or of the extension beyond the last point).
    double b = (i + 2 < t.deflection.size()) ? t.deflection[i + 1] : hi;
    if (b <= a) b = hi;  // a sits exactly on a breakpoint handled by the next segment
    b = std::min(b, hi);
    sum += segment_integral(t, i, a, b);
    a = b;
  }
  return x >= 0.0 ? sum : -sum;
}

double table_max_slope(const ForceTable& t) {
  double m = 0.0;
  for (std::size_t i = 0; i + 1 < t.deflection.size(); ++i) m = std::max(m, std::abs(slope(t, i)));
  return m;
}

}  // namespace mbsflow
