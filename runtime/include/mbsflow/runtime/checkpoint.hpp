#pragma once
// Checkpoints of a run. Every so often (wall clock) the run loop stops between two steps,
// has its sink store every snapshot so far, and hands its whole state (where the loop
// is, what was written, the stepper's state: mbsflow/methods/state_archive.hpp) to
// write(). A run given such a state in `resume` goes on from it: the same steps, the
// same snapshots, bit for bit what the run would have done without the interruption.
// What surrounds the state in a checkpoint file (the model, the command) is the
// caller's: apps/ keeps it in FILE.ckpt (docs/reliability.md).
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mbsflow {

struct Checkpointing {
  double every_s = 0.0;  // wall-clock seconds between checkpoints; 0: none are written
  std::function<void(std::vector<std::uint8_t>&& state)> write;
  std::vector<std::uint8_t> resume;  // a state write() was given, to go on from; empty: from t_start
  std::string resume_from;           // names it in messages ("checkpoint run.ckpt")
};

// Whether the next checkpoint is due: every_s after the last one (or the start).
class CheckpointTimer {
 public:
  explicit CheckpointTimer(const Checkpointing* c) : every_(c && c->write ? c->every_s : 0.0), last_(Clock::now()) {}
  bool due() {
    if (!(every_ > 0.0)) return false;
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - last_).count() < every_) return false;
    last_ = now;
    return true;
  }

 private:
  using Clock = std::chrono::steady_clock;
  double every_;
  Clock::time_point last_;
};

}  // namespace mbsflow
