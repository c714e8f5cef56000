#pragma once
// The macro steps of a loosely coupled run as an advancer (run_loop.hpp), in one process
// (run_loose) or in a worker (run_loose_part): one flow-graph run of steps_per_run() macro
// steps at a fixed macro step, or one adaptive macro step, taken again from its start with
// a shorter H while its coupling error is above the tolerance, down to
// smallest_macro_fraction of lo.macro_step (then it is taken and counted in
// over_tolerance). After each advance: the observer's reached(), the snapshots the
// submodels kept (projected already), then the macro-step end as a step.
#include <functional>
#include <memory>
#include <vector>

#include "loose_rounds.hpp"
#include "run_loop.hpp"

namespace mbsflow::loose {

// In a worker, the adaptive decisions every worker takes alike: worst(attempt, e) the
// largest error over all workers (attempt numbers the tries), retake(index) before a
// macro step to end `index` is taken again, after the local parts went back.
struct AcrossWorkers {
  std::function<double(long attempt, double e)> worst = [](long, double e) { return e; };
  std::function<void(long index)> retake = [](long) {};
};

class LooseAdvancer final : public Advancer {
 public:
  // parts[q]: null where submodel q runs elsewhere; y: the whole model's state in its
  // layout `global`, into which the local submodels' snapshots go.
  LooseAdvancer(const RunOptions& o, const LooseOptions& lo, std::vector<std::unique_ptr<LoosePart>>& parts,
                LooseRounds& rounds, MacroGrid& grid, LooseStats& st, const StateLayout& global, Eigen::VectorXd y,
                AcrossWorkers across = {});

  LoosePosition at;  // where the run is: macro steps done, the next snapshot, the adaptive walk

  bool done() const override { return grid_.reached_end(at.done); }
  void advance(RunObserver& to) override;
  // The submodel count, the position, the adaptive walk's counts, the local submodels.
  void save(StateWriter& w) override;
  // Reads back what save() wrote; returns the time the run goes on from.
  double restore(StateReader& in);

 private:
  void adaptive_step();
  void reach(long m, RunObserver& to);

  const LooseOptions& lo_;
  std::vector<std::unique_ptr<LoosePart>>& parts_;
  LooseRounds& rounds_;
  MacroGrid& grid_;
  LooseStats& st_;
  const StateLayout& global_;
  AcrossWorkers across_;
  Eigen::VectorXd y_;  // a snapshot gathered from the local submodels
};

}  // namespace mbsflow::loose
