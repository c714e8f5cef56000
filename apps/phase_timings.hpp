#pragma once
// mbsflow run --timings: how long each phase of a run's set-up took and how much memory
// the process held after it, on stderr, so that a slow or large start can be traced to
// its phase (reading, checking, the results file, cutting, set-up, steps).
#include <chrono>
#include <string>

namespace mbsflow::cli {

struct MemoryUse {
  double resident_bytes = 0.0;  // now
  double peak_bytes = 0.0;      // the process's high-water mark so far
};
// From /proc/self/status; zeros where it cannot be read.
MemoryUse memory_use();

class PhaseTimings {
 public:
  explicit PhaseTimings(bool enabled);
  // Prints the phase that ended now: its seconds, then resident and peak memory (and per
  // body when bodies > 0).
  void mark(const std::string& phase, long bodies = 0);

 private:
  using Clock = std::chrono::steady_clock;
  bool enabled_;
  Clock::time_point start_, last_;
};

}  // namespace mbsflow::cli
