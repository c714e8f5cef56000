#pragma once
// The one loop of a tightly coupled run, whether all its submodels run in this process
// (run_partitioned) or some run in other workers (worker_tight.cpp): RK4 with ghost values
// exchanged at every stage, or DOPRI5 with them exchanged at every stage of an attempt and
// the error norm the one global reduction per attempt. Where the values come from is the
// BoundaryExchange's business, where the results go the TightOutput's.
#include <oneapi/tbb/enumerable_thread_specific.h>

#include <chrono>
#include <cstdint>
#include <numeric>
#include <vector>

#include "boundary_exchange.hpp"
#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow {

// Time spent in stage work, per thread.
class BusyClock {
 public:
  template <class F>
  void time(F f) {
    const auto start = std::chrono::steady_clock::now();
    f();
    busy_.local() += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  double total() const { return std::accumulate(busy_.begin(), busy_.end(), 0.0); }

 private:
  tbb::enumerable_thread_specific<double> busy_{0.0};
};

// Where the loop of a tightly coupled run is between two steps, whatever the partition:
// the steps taken (RK4: the next step's index), and for DOPRI5 the time, the step to try,
// the controller's memory (StateWriter bytes of dopri5::Controller::save), the next
// output's index and the counts. A checkpoint keeps it with the global state.
struct TightPoint {
  long steps = 0, rejected = 0, evaluations = 0;
  double t = 0.0, h = 0.0;
  long next_out = 1;
  std::vector<std::uint8_t> controller;
};

// A tightly coupled run's part of a checkpoint: the point and the global state y (run in
// one process or on workers, it is the same).
void save_tight_point(StateWriter& w, const TightPoint& p, const Eigen::VectorXd& y);
// Reads them back; y must be of `size` numbers.
TightPoint read_tight_point(StateReader& in, Eigen::Index size, Eigen::VectorXd& y);

// Where a tightly coupled run's results go: a sink in this process, or the coordinator.
class TightOutput {
 public:
  virtual ~TightOutput() = default;
  // After `steps` steps, at t: throws to stop the run (diverged, interrupted, stopped
  // elsewhere); reports progress, and with snapshot >= 0 the local submodels' states
  // (own bodies of x[0]) as snapshot number `snapshot`.
  virtual void step_done(long steps, double t, long snapshot) = 0;
  // Dense output at t, snapshot number `index`: the local submodels' own entries of y
  // (global layout) are set, drivers not yet imposed.
  virtual void dense(long index, double t, Eigen::VectorXd& y) = 0;
  // False: the run writes no snapshots between steps (no dense output to compute).
  virtual bool wants_dense() const { return true; }
  // Checkpoints: whether one is due now (asked between steps), and taking it; the local
  // submodels' x[0] hold the state at point.t.
  virtual bool checkpoint_due() { return false; }
  virtual void checkpoint(const TightPoint& point) { (void)point; }
};

struct TightRun {
  const Decomposition& d;
  std::vector<partitioned::Part*> parts;  // null where the submodel runs elsewhere
  const RunOptions& o;
  BoundaryExchange& exchange;
  TightOutput& output;
  bool barriers = false;       // a barrier after every stage (the seed's scheme)
  BusyClock* clock = nullptr;  // times the stage work
  const TightPoint* start = nullptr;  // go on from here (the parts' x[0] set); null: from t_start
};

struct TightCounts {
  long steps = 0, rejected = 0, evaluations = 0;  // of the whole model, as one process counts them
};

// Runs o.method (rk4 or dopri5) from o.t_start to o.t_end; call it inside the task arena.
TightCounts run_tight_coupling(const TightRun& run);

// The stage count of a tightly coupled method (InputError for a method that has none).
int tight_stages(Method m);

}  // namespace mbsflow
