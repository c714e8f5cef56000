#include "phase_timings.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "huge_pages.hpp"

namespace mbsflow::cli {

MemoryUse memory_use() {
  MemoryUse m;
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    double kib = 0.0;
    fields >> key >> kib;
    if (key == "VmRSS:") m.resident_bytes = 1024.0 * kib;
    if (key == "VmHWM:") m.peak_bytes = 1024.0 * kib;
  }
  return m;
}

PhaseTimings::PhaseTimings(bool enabled) : enabled_(enabled), start_(Clock::now()), last_(start_) {
  if (!enabled_) return;
  std::fprintf(stderr, "mbsflow: malloc with transparent huge pages: %s\n",
               huge_pages_on() ? "on"
                               : "off (a model file under 16 MiB: MBSFLOW_HUGE_PAGES=1 turns them on; or "
                                 "MBSFLOW_HUGE_PAGES=0, the caller's GLIBC_TUNABLES, valgrind, none from the kernel)");
  std::fprintf(stderr, "mbsflow: %-34s %9s %9s %11s %11s %10s\n", "phase", "s", "total s", "resident MB", "peak MB", "B/body");
}

void PhaseTimings::mark(const std::string& phase, long bodies) {
  if (!enabled_) return;
  const auto now = Clock::now();
  const MemoryUse m = memory_use();
  char per_body[32] = "";
  if (bodies > 0) std::snprintf(per_body, sizeof per_body, "%10.0f", m.resident_bytes / static_cast<double>(bodies));
  std::fprintf(stderr, "mbsflow: %-34s %9.3f %9.3f %11.1f %11.1f %s\n", phase.c_str(),
               std::chrono::duration<double>(now - last_).count(), std::chrono::duration<double>(now - start_).count(),
               m.resident_bytes / 1048576.0, m.peak_bytes / 1048576.0, per_body);
  last_ = now;
}

}  // namespace mbsflow::cli
