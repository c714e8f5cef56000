#pragma once
// Nonlinear force-deflection characteristic: piecewise linear through the points,
// extended linearly beyond the first and last segment.
#include <vector>

namespace mbsflow {

struct ForceTable {
  std::vector<double> deflection;  // strictly increasing
  std::vector<double> force;
  bool empty() const { return deflection.empty(); }
};

double table_force(const ForceTable& t, double x);
// d force / d x at x: the slope of the segment (or end extension) that holds x.
double table_slope(const ForceTable& t, double x);
// Integral of the force from 0 to x (the stored elastic energy of that axis).
double table_energy(const ForceTable& t, double x);
// Largest slope of the table (for the stable-step estimate).
double table_max_slope(const ForceTable& t);

}  // namespace mbsflow
