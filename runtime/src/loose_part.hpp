#pragma once
// One submodel's side of loose coupling, shared by the one-process run (run_loose) and the
// workers of a run across processes. x[0] is the submodel's state; between macro steps its
// ghost slots hold the owners' values at the last macro-step end (what was exchanged), and
// the samples are these local vectors at the last few macro-step ends. At the start,
// x[1..k] hold the own bodies' past y0 - jH f0 (j = 1..k) for the owners to exchange too.
#include <deque>
#include <tuple>
#include <memory>
#include <vector>

#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "partitioned_state.hpp"
#include "step_grid.hpp"

namespace mbsflow::loose {

struct CouplingError {
  double position = 0.0, velocity = 0.0;  // largest ghost distance, extrapolated vs exchanged
};

class LoosePart {
 public:
  LoosePart(const Model& model, const Submodel& sub, const RunOptions& o, int extrapolation, int max_lag);

  partitioned::Part part;

  // Own bodies' derivative at t0 with the true ghosts in x[0]; x[j] = x[0] - jH f0, j = 1..k.
  void make_past(double t0, double H);
  // After the ghost slots of x[1..k] and x[0] hold the owners' past and initial values.
  void start(double t0, double H);
  // Integrates the own bodies from t0 to t1 with the ghosts extrapolated.
  void integrate(double t0, double t1);
  // After the ghost slots of x[0] got the owners' values at t1: how far the extrapolation
  // was off; push makes x[0] the newest sample.
  CouplingError error(double t1);
  void push(double t1);
  void save();  // x[0] and the integrator's step, to take a macro step again
  void restore(long index);  // forgets what keep(index) kept

  // The own state at macro-step end `index` (time t), kept while a lagged neighbour may
  // still need it (max_lag + 1 of them).
  void keep(long index, double t);
  const Eigen::VectorXd& kept(long index) const;
  double kept_time(long index) const;

  long steps = 0, rejected = 0, evaluations = 0;

 private:
  struct Ghosted;  // the local system with extrapolated ghosts (loose_part.cpp)
  std::vector<double> weights(double t) const;
  void extrapolate_ghosts(double t, Eigen::VectorXd& y) const;

  const RunOptions& o_;
  int order_;
  int lag_;
  std::deque<std::tuple<long, double, Eigen::VectorXd>> kept_;  // index, time, x[0]
  std::deque<std::pair<double, Eigen::VectorXd>> samples_;  // newest first
  std::unique_ptr<Rk4> rk4_;
  std::unique_ptr<Dopri5> dopri5_;
  double h_ = 0.0;  // DOPRI5's next step
  Eigen::VectorXd saved_, work_, guess_;
  double saved_h_ = 0.0;
};

// Ghost slots of x[s] of every part here (parts indexed by submodel, null where it runs
// elsewhere) from owners here: from(owner) is the owner's state vector to copy from (its
// x[s], or what it kept). Owners elsewhere are left to the caller.
template <class From>
void copy_local_ghosts(std::vector<std::unique_ptr<LoosePart>>& parts, int s, From from) {
  for (auto& me : parts) {
    if (!me) continue;
    for (const Submodel::Exchange& e : me->part.sub->exchanges)
      if (const LoosePart* owner = parts[static_cast<std::size_t>(e.neighbour)].get())
        partitioned::copy_ghosts(owner->part.system.layout(), from(*owner), e, me->part, s);
  }
}

// Where the macro step from t with length H ends: at t + H, or on the next output time
// (grid.time of the output step, as the tight run has it) when it reaches that.
double next_macro_end(const StepGrid& grid, long output_every, long next_out, double t, double H, bool* on_output);

}  // namespace mbsflow::loose
