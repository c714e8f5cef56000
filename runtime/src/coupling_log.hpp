#pragma once
// The coupling records of a loosely coupled run, merged per macro-step end over the
// submodels (and workers) that reported on it: the largest error and lag.
#include <algorithm>
#include <map>
#include <vector>

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

 private:
  std::map<long, CouplingRecord> by_index_;
};

}  // namespace mbsflow::loose
