#include "loose_advancer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "mbsflow/error.hpp"

namespace mbsflow::loose {

LooseAdvancer::LooseAdvancer(const RunOptions& o, const LooseOptions& lo, std::vector<std::unique_ptr<LoosePart>>& parts,
                             LooseRounds& rounds, MacroGrid& grid, LooseStats& st, const StateLayout& global,
                             Eigen::VectorXd y, AcrossWorkers across)
    : at{0, 1, adaptive_start(o, lo)}, lo_(lo), parts_(parts), rounds_(rounds), grid_(grid), st_(st), global_(global),
      across_(std::move(across)), y_(std::move(y)) {}

void LooseAdvancer::advance(RunObserver& to) {
  if (lo_.coupling_tol > 0.0) {
    adaptive_step();
    reach(at.walk.m, to);
    return;
  }
  const long m = at.done;
  const int most = grid_.steps_per_run();
  grid_.extend(m + most);
  const int n = static_cast<int>(std::min<long>(most, grid_.last() - m));
  const std::string failure = rounds_.run(m, n);
  if (!failure.empty()) throw RunError(failure);
  reach(m + n, to);
  grid_.forget_before(m + n - ends_kept(lo_));
}

void LooseAdvancer::adaptive_step() {
  AdaptiveWalk& walk = at.walk;
  const double order = lo_.extrapolation + 1.0;
  for (;;) {
    const long m = walk.m;
    const double t = walk.t;
    grid_.add(m, walk.H);
    const double t1 = grid_.end(m + 1);
    for (auto& p : parts_)
      if (p) p->save();
    const std::string failure = rounds_.run(m, 1);
    if (!failure.empty()) throw RunError(failure);
    rounds_.catch_up(m + 1);  // every neighbour value of the new end: the coupling errors
    const double e = across_.worst(++walk.attempt, rounds_.worst(m + 1).position);
    // Step-size factor from the error model e ~ H^(order).
    const double factor = std::clamp(0.9 * std::pow(lo_.coupling_tol / std::max(e, 1e-300), 1.0 / order), 0.2, 2.0);
    const double smallest = lo_.macro_step * smallest_macro_fraction;
    if (e > lo_.coupling_tol && t1 - t > smallest * (1.0 + 1e-9)) {  // too far off: back to t, shorter
      for (auto& p : parts_)
        if (p) p->restore(m + 1);
      rounds_.discard(m + 1);
      across_.retake(m + 1);
      walk.H = std::max(smallest, (t1 - t) * factor);
      ++st_.rejected;
      continue;
    }
    if (e > lo_.coupling_tol) ++st_.over_tolerance;  // at the smallest macro step: taken, counted
    grid_.forget_before(m + 1 - 8);
    walk.m = m + 1;
    walk.H = std::min(lo_.macro_step, (t1 - t) * factor);  // no longer than the one the overlap was chosen for
    walk.t = t1;
    return;
  }
}

// At macro-step end m: the snapshots up to it, which the submodels kept from their dense
// output, then the end as a step.
void LooseAdvancer::reach(long m, RunObserver& to) {
  const double t = grid_.end(m);
  to.reached(t);
  at.done = m;
  for (long& k = at.next_output; to.wants_dense() && k <= grid_.outputs() && at_or_before(grid_.output_time(k), t); ++k) {
    for (auto& p : parts_)
      if (p) p->take_snapshot(k, global_, y_);
    to.dense(k, grid_.output_time(k), y_, true);
  }
  to.step_done(m, t, -1);
}

void LooseAdvancer::save(StateWriter& w) {
  w.integer(static_cast<std::int64_t>(parts_.size()));
  save_position(w, at, grid_);
  w.integer(st_.rejected);
  w.integer(st_.over_tolerance);
  for (const auto& p : parts_)
    if (p) p->save(w);
}

double LooseAdvancer::restore(StateReader& in) {
  const auto submodels = in.integer(1, INT32_MAX);
  if (submodels != static_cast<std::int64_t>(parts_.size()))
    in.fail("it is of a run cut into " + std::to_string(submodels) + " submodels, not " + std::to_string(parts_.size()));
  restore_position(in, at, grid_);
  st_.rejected = in.integer(0, INT64_MAX);
  st_.over_tolerance = in.integer(0, INT64_MAX);
  for (auto& p : parts_)
    if (p) p->restore(in);
  return grid_.end(at.done);
}

}  // namespace mbsflow::loose
