#pragma once
// The fixed-step time grid of an RK4 run, shared by the sequential and partitioned loops so
// that both step through bit-identical times.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "mbsflow/error.hpp"

namespace mbsflow {

struct StepGrid {
  double t_start = 0.0, t_end = 0.0, h = 0.0;
  long steps = 0;  // steps of h that cover [t_start, t_end]; the last one may be shorter
  double time(long n) const { return n >= steps ? t_end : t_start + static_cast<double>(n) * h; }
};

// More steps than this are refused: a run would never end, and beyond 2^53 steps the
// times t_start + n h are no longer distinct.
inline constexpr double max_grid_steps = 0x1p53;

inline StepGrid step_grid(double t_start, double t_end, double h) {
  StepGrid g{t_start, t_end, h, 0};
  const double x = (t_end - t_start) / h;
  if (!(x >= 0.0 && x <= max_grid_steps)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "{step=%.6g} over [%.6g, %.6g] makes %.3g steps, more than a run can take (2^53)", h,
                  t_start, t_end, x);
    throw InputError(buf);
  }
  const double r = std::round(x);
  g.steps = std::abs(x - r) <= 1e-9 * std::max(1.0, x) ? static_cast<long>(r) : static_cast<long>(std::ceil(x));
  return g;
}

// How close to t_end an adaptive run counts as there (1e-12, relative): the integrators
// step while t_end - t is larger, and a step that ends this close lands on t_end.
inline double end_tolerance(double t_end) { return 1e-12 * std::max(1.0, std::abs(t_end)); }
inline bool reached_end(double t, double t_end) { return t_end - t <= end_tolerance(t_end); }

// Where an adaptive step of `taken` from t lands: exactly on t_end when within rounding.
inline double landed_time(double t, double taken, double t_end) { return reached_end(t + taken, t_end) ? t_end : t + taken; }

// Steps per chunk of RK4: snapshots fall on chunk ends; at most 64 steps unrolled.
inline int chunk_length(int output_every) {
  for (int c = std::min(output_every, 64); c > 1; --c)
    if (output_every % c == 0) return c;
  return 1;
}

}  // namespace mbsflow
