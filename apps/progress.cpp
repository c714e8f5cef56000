#include "progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace mbsflow::cli {

ProgressLine::ProgressLine(double t_start, double t_end, bool enabled)
    : t0_(t_start), t1_(t_end), enabled_(enabled && ::isatty(STDERR_FILENO)), start_(Clock::now()), last_(start_) {}

void ProgressLine::update(double t, long steps) {
  if (!enabled_) return;
  const auto now = Clock::now();
  if (now - last_ < std::chrono::milliseconds(250)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = (t - t0_) / (t1_ - t0_);
  const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
  std::fprintf(stderr, "\r\033[Kt = %.4g s of %.4g s  %5.1f%%  %.3g steps/s  ETA %.0f s", t, t1_, 100.0 * fraction,
               static_cast<double>(steps) / elapsed, eta);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::finish() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
  drawn_ = false;
}

}  // namespace mbsflow::cli
