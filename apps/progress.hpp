#pragma once
// A progress line on stderr for long runs: simulated time, percent, steps/s, ETA.
// Shown only when stderr is a terminal and not --quiet; redrawn at most 4 times a second.
#include <chrono>

namespace mbsflow::cli {

class ProgressLine {
 public:
  ProgressLine(double t_start, double t_end, bool enabled);
  void update(double t, long steps);
  void finish();  // clears the line

 private:
  using Clock = std::chrono::steady_clock;
  double t0_, t1_;
  bool enabled_, drawn_ = false;
  Clock::time_point start_, last_;
};

}  // namespace mbsflow::cli
