#pragma once
// A sink that keeps every snapshot in memory, for tests.
#include <vector>

#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow::test {

struct MemorySink : ResultSink {
  SnapshotContent wanted;
  std::vector<double> times;
  std::vector<Snapshot> snapshots;
  std::vector<Eigen::VectorXd> states;
  bool ended = false;
  SnapshotContent content() const override { return wanted; }
  void begin(const MultibodySystem&) override {}
  void write(Snapshot&& s) override {
    times.push_back(s.t);
    states.push_back(s.state);
    snapshots.push_back(std::move(s));
  }
  void end() override { ended = true; }
};

// The same times and bit for bit the same states.
inline bool same_snapshots(const MemorySink& a, const MemorySink& b) {
  return a.times == b.times && a.states == b.states;
}

}  // namespace mbsflow::test
