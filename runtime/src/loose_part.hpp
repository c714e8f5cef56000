#pragma once
// One submodel's side of loose coupling, shared by the one-process run (run_loose) and the
// workers of a run across processes. x[0] is the submodel's state. Its ghosts follow a
// polynomial extrapolation of the samples it took of each neighbour: per neighbour, the
// last few of that neighbour's states at macro-step ends, which may be of different ages
// for different neighbours (asynchronous runs). The own state at every macro-step end is
// published for the neighbours in this process; remote ones get it as a message.
#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "partitioned_state.hpp"

namespace mbsflow::loose {

struct CouplingError {
  double position = 0.0, velocity = 0.0;  // largest ghost distance, extrapolated vs sent
};

class LoosePart {
 public:
  // `retain`: how many published macro-step ends to keep for the neighbours here.
  LoosePart(const Model& model, const Submodel& sub, const RunOptions& o, Method method, int extrapolation, int retain);

  partitioned::Part part;

  // Own bodies' derivative at t0 with the true ghosts in x[0]; x[j] = x[0] - jH f0, j = 1..k.
  void make_past(double t0, double H);
  // After the ghost slots of x[1..k] and x[0] hold the owners' past and initial values:
  // they become the first samples (macro-step ends -k..0), and x[0] is published as end 0.
  void start(double t0, double H);
  // Integrates the own bodies from t0 to t1 with the ghosts extrapolated: the submodel's
  // stepper (any registered method) takes its own steps inside the macro step. The
  // snapshots numbered `outputs` (index, time in (t0, t1]) are kept from its dense output,
  // projected like a step's end (its state where a step ends on one).
  void integrate(double t0, double t1, const std::vector<std::pair<long, double>>& outputs = {});
  // Own bodies of kept snapshot `index` into y (global layout); it is then forgotten.
  void take_snapshot(long index, const StateLayout& global, Eigen::VectorXd& y);

  // Before the macro step from end `index`: the borrowed bodies (an overlap) take their
  // owners' values at that end, if they are in (not with a lag).
  void reset_borrowed(long index);
  // After the macro step to end `index` (time t): what this submodel has for the bodies of
  // each exchange that are joined to own bodies (extrapolated ghosts, integrated borrowed
  // bodies), kept until that end's samples are taken.
  void predict(long index, double t);
  // Neighbour exchange e's sample: its bodies e.from at macro-step end `index` (time t),
  // packed (partitioned::pack_bodies, in the order of e.to). take() makes it the newest
  // and returns how far the prediction for that end was from it (the coupling error),
  // if one was made; prediction_error() tells the same without taking it.
  std::optional<CouplingError> take(std::size_t e, long index, double t, const double* packed);
  std::optional<CouplingError> prediction_error(std::size_t e, long index, const double* packed) const;
  long taken(std::size_t e) const { return history_[e].front().index; }

  // The own state at macro-step end `index`, for the neighbours in this process (any thread).
  void publish(long index, double t);
  long published() const;
  // f(index, state) for every published end kept, oldest first.
  template <class F>
  void each_published(F f) const {
    std::lock_guard lock(board_mutex_);
    for (const Published& p : board_) f(p.index, p.x);
  }
  // Bodies of the published end `index` packed into out, and its time.
  double pack_published(long index, const std::vector<int>& bodies, double* out) const;

  // x[0], the integrator's step and the neighbour samples, to take a macro step again
  void save();
  // Back to the saved state and samples; forgets the ends from `index` on and the
  // snapshots since.
  void restore(long index);

  // Checkpoints, at a macro-step end that every submodel here has reached and whose
  // snapshots were taken: the state, the method's state, the counts, the neighbour
  // samples and predictions, and the published ends the neighbours may still take.
  void save(StateWriter& w) const;
  void restore(StateReader& in);

  long steps = 0, rejected = 0, evaluations = 0;

 private:
  // The local system with extrapolated ghosts: what the stepper integrates.
  void ghosted_rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt);
  struct Sample {
    long index;
    double t;
    std::vector<double> bodies;  // packed, 13 numbers a ghost
  };
  struct Published {  // also a snapshot: its number, time and local state
    long index;
    double t;
    Eigen::VectorXd x;
  };
  std::deque<Published> snapshots_;
  std::size_t saved_snapshots_ = 0;
  // Exchange e's bodies at `positions` (in its order) extrapolated to t, packed.
  void extrapolate(std::size_t e, double t, const std::vector<int>& positions, std::vector<double>& out) const;
  void extrapolate_ghosts(double t, Eigen::VectorXd& y);

  const RunOptions& o_;
  int order_;
  std::size_t retain_;
  std::vector<std::deque<Sample>> history_, saved_history_;  // per exchange, newest first
  std::vector<std::deque<Sample>> predicted_;  // per exchange, oldest first, its near bodies
  // Per exchange: positions of its ghosts (extrapolated) and of its borrowed bodies.
  std::vector<std::vector<int>> ghost_at_, borrowed_at_;
  std::vector<std::vector<int>> ghost_slots_;  // per exchange, its ghosts' local indices
  std::vector<int> ghost_bodies_;              // all ghosts' local indices
  mutable std::mutex board_mutex_;
  std::deque<Published> board_;  // oldest first
  StepperSystem system_;
  std::unique_ptr<Stepper> stepper_;
  Eigen::VectorXd saved_, work_;
  std::vector<double> ghost_buffer_;
  double saved_h_ = 0.0;
};

// Ghost slots of x[s] of every part here (parts indexed by submodel, null where it runs
// elsewhere) from the owners here (their x[s]). Owners elsewhere are left to the caller.
inline void copy_local_ghosts(std::vector<std::unique_ptr<LoosePart>>& parts, int s) {
  for (auto& me : parts) {
    if (!me) continue;
    for (const Submodel::Exchange& e : me->part.sub->exchanges)
      if (const LoosePart* owner = parts[static_cast<std::size_t>(e.neighbour)].get())
        partitioned::copy_ghosts(owner->part, e, me->part, s);
  }
}

// The macro-step ends of a run, end(0) = t_start, and its snapshots, which do not depend
// on them: number k = 1 .. outputs() at output_time(k), on the grid of the run's step
// (RunOptions' output_every or output_interval, rounded onto it), the last at t_end. With
// a fixed macro step the ends are made as the run goes and forgotten behind it (a long
// run has millions); an adaptive run adds them itself.
class MacroGrid {
 public:
  MacroGrid(const RunOptions& o, double H);  // H = 0: adaptive, the run add()s the ends
  double end(long m) const { return ends_[static_cast<std::size_t>(m - base_)]; }
  // The tight grid's step nearest to end m (progress reports).
  long tight_step(long m) const { return std::lround((end(m) - grid_.t_start) / grid_.h); }
  long last() const { return base_ + static_cast<long>(ends_.size()) - 1; }  // the latest end known
  bool complete() const { return reached_end(last()); }
  bool reached_end(long m) const { return end(m) >= grid_.t_end; }
  // Fixed macro step: makes the ends up to m known (or up to t_end, if it comes first).
  void extend(long m);
  // End m + 1, a macro step H after end m, or t_end where it reaches it; any later ends
  // are forgotten (a macro step taken again).
  void add(long m, double H);
  void forget_before(long m);
  // The ends known, as sums of macro steps: a resumed run must go on from the same sums.
  void save(StateWriter& w) const;
  void restore(StateReader& in);
  // Macro steps per flow-graph run: about one output interval's worth, at most 64.
  int steps_per_run() const;
  long outputs() const { return outputs_; }
  double output_time(long k) const { return grid_.time(std::min(k * every_, grid_.steps)); }
  long output_step(long k) const { return std::min(k * every_, grid_.steps); }
  // The snapshots whose times lie in (t0, t1] (within rounding): (number, time), in order.
  std::vector<std::pair<long, double>> outputs_in(double t0, double t1) const;

 private:
  const RunOptions& o_;
  double H_;
  StepGrid grid_;
  long every_ = 1, outputs_ = 0, base_ = 0;
  std::deque<double> ends_;
};

// Within rounding of a macro-step end: what counts as on or before it.
inline bool at_or_before(double t, double end) { return t <= end + 1e-12 * std::max(1.0, std::abs(end)); }

}  // namespace mbsflow::loose
