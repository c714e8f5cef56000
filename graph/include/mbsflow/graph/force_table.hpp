#pragma once
// Nonlinear force-deflection characteristic: piecewise linear through the points,
// extended linearly beyond the first and last segment.
#include <array>
#include <vector>

#include "mbsflow/graph/rare_value.hpp"

namespace mbsflow {

struct ForceTable {
  std::vector<double> deflection;  // strictly increasing
  std::vector<double> force;
  bool empty() const { return deflection.empty(); }
};

// A bushing's six tables (x, y, z, rx, ry, rz). Most joints have none, so they are held
// behind one pointer: a Joint stays small (a million of them) and copies as a value.
// Reading an axis of a joint without tables gives an empty table; writing one makes room.
class AxisTables {
 public:
  using Array = std::array<ForceTable, 6>;

  const ForceTable& operator[](std::size_t axis) const { return all()[axis]; }
  ForceTable& operator[](std::size_t axis) { return t_.edit()[axis]; }
  const Array& all() const { return t_.get(); }
  Array::const_iterator begin() const { return all().begin(); }
  Array::const_iterator end() const { return all().end(); }
  bool any() const {
    for (const ForceTable& t : all())
      if (!t.empty()) return true;
    return false;
  }

 private:
  RareValue<Array> t_;
};

double table_force(const ForceTable& t, double x);
// d force / d x at x: the slope of the segment (or end extension) that holds x.
double table_slope(const ForceTable& t, double x);
// Integral of the force from 0 to x (the stored elastic energy of that axis).
double table_energy(const ForceTable& t, double x);
// Largest slope of the table (for the stable-step estimate).
double table_max_slope(const ForceTable& t);

}  // namespace mbsflow
