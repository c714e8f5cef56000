#pragma once
// The coupling records of a loosely coupled run, merged per macro-step end over the
// submodels (and workers) that reported on it: the largest error and lag.
#include <algorithm>
#include <cstdint>
#include <map>
#include <vector>

#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow::loose {

class CouplingLog {
 public:
  void add(const CouplingRecord& r) {
    auto [it, added] = by_index_.try_emplace(r.index, r);
    if (added) return;
    CouplingRecord& m = it->second;
    m.position_error = std::max(m.position_error, r.position_error);
    m.velocity_error = std::max(m.velocity_error, r.velocity_error);
    m.lag = std::max(m.lag, r.lag);
  }
  std::vector<CouplingRecord> records() const {  // by macro-step end
    std::vector<CouplingRecord> out;
    out.reserve(by_index_.size());
    for (const auto& [index, r] : by_index_) out.push_back(r);
    return out;
  }
  // Checkpoints of a loosely coupled run keep the records so far.
  void save(StateWriter& w) const {
    w.integer(static_cast<std::int64_t>(by_index_.size()));
    for (const auto& [index, r] : by_index_) {
      w.integer(r.index);
      for (double v : {r.t_start, r.t_end, r.position_error, r.velocity_error}) w.real(v);
      w.integer(r.lag);
    }
  }
  void restore(StateReader& in) {
    by_index_.clear();
    for (auto n = in.integer(0, INT64_MAX); n > 0; --n) {
      CouplingRecord r;
      r.index = in.integer(0, INT64_MAX);
      for (double* v : {&r.t_start, &r.t_end, &r.position_error, &r.velocity_error}) *v = in.real();
      r.lag = static_cast<int>(in.integer(0, INT32_MAX));
      by_index_[r.index] = r;
    }
  }

 private:
  std::map<long, CouplingRecord> by_index_;
};

}  // namespace mbsflow::loose
