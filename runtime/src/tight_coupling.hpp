#pragma once
// The one loop of a tightly coupled run, whether all its submodels run in this process
// (run_partitioned) or some run in other workers (worker_tight.cpp): RK4 with ghost values
// exchanged at every stage, or DOPRI5 with them exchanged at every stage of an attempt and
// the error norm the one global reduction per attempt. Where the values come from is the
// BoundaryExchange's business, where the results go the RunObserver's (run_loop.hpp).
#include <oneapi/tbb/enumerable_thread_specific.h>

#include <chrono>
#include <cstdint>
#include <numeric>
#include <vector>

#include "boundary_exchange.hpp"
#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "run_loop.hpp"

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

// A tightly coupled run's part of a checkpoint: the point, then the global state y (run in
// one process or on workers, it is the same).
void save_tight_point(StateWriter& w, const TightPoint& p);
void save_tight_point(StateWriter& w, const TightPoint& p, const Eigen::VectorXd& y);
// Reads them back; y must be of `size` numbers.
TightPoint read_tight_point(StateReader& in, Eigen::Index size, Eigen::VectorXd& y);

struct TightRun {
  const Decomposition& d;
  std::vector<partitioned::Part*> parts;  // null where the submodel runs elsewhere
  const RunOptions& o;
  BoundaryExchange& exchange;
  RunObserver& output;  // the snapshots: the state in the local parts' x[0], dense output of their own entries
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
