#pragma once
// A sink that keeps every snapshot in memory, for tests.
#include <algorithm>
#include <string>
#include <vector>

#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow::test {

struct MemorySink : ResultSink {
  SnapshotContent wanted;
  std::vector<double> times;
  std::vector<Snapshot> snapshots;
  std::vector<Eigen::VectorXd> states;
  std::vector<CouplingRecord> coupling;
  bool ended = false;
  SnapshotContent content() const override { return wanted; }
  void begin(const MultibodySystem&) override {}
  void write(Snapshot&& s) override {
    times.push_back(s.t);
    states.push_back(s.state);
    snapshots.push_back(std::move(s));
  }
  void write_coupling(const std::vector<CouplingRecord>& records) override { coupling = records; }
  void end() override { ended = true; }
  // Checkpoints: the snapshots after the first n are dropped, as a results file's rows are.
  std::string identity() const override { return "memory"; }
  void resume(const MultibodySystem&, long n, const std::string& id) override {
    if (id != "memory" || n > static_cast<long>(times.size())) throw InputError("not these results");
    times.resize(static_cast<std::size_t>(n));
    states.resize(static_cast<std::size_t>(n));
    snapshots.resize(static_cast<std::size_t>(n));
  }
};

// The same times and bit for bit the same states.
inline bool same_snapshots(const MemorySink& a, const MemorySink& b) {
  return a.times == b.times && a.states == b.states;
}

// The same coupling records, every field bit for bit.
inline bool same_records(const std::vector<CouplingRecord>& a, const std::vector<CouplingRecord>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const CouplingRecord& x, const CouplingRecord& y) {
    return x.index == y.index && x.t_start == y.t_start && x.t_end == y.t_end && x.position_error == y.position_error &&
           x.velocity_error == y.velocity_error && x.lag == y.lag;
  });
}

}  // namespace mbsflow::test
