#pragma once
// One submodel's side of loose coupling, shared by the one-process run (run_loose) and the
// workers of a run across processes. x[0] is the submodel's state. Its ghosts follow a
// polynomial extrapolation of the samples it took of each neighbour: per neighbour, the
// last few of that neighbour's states at macro-step ends, which may be of different ages
// for different neighbours (asynchronous runs). The own state at every macro-step end is
// published for the neighbours in this process; remote ones get it as a message.
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "partitioned_state.hpp"
#include "step_grid.hpp"

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
  // Integrates the own bodies from t0 to t1 with the ghosts extrapolated.
  void integrate(double t0, double t1);

  // Before the macro step to end `index` (time t): what the ghosts are extrapolated to
  // there, kept until that end's samples are taken.
  void predict(long index, double t);
  // Neighbour exchange e's sample: its bodies e.from at macro-step end `index` (time t),
  // packed (partitioned::pack_bodies, in the order of e.to). take() makes it the newest
  // and returns how far the prediction for that end was from it (the coupling error),
  // if one was made; error() is how far the extrapolation from the samples taken so far is.
  std::optional<CouplingError> take(std::size_t e, long index, double t, const double* packed);
  CouplingError error(std::size_t e, double t, const double* packed) const;
  long taken(std::size_t e) const { return history_[e].front().index; }

  // The own state at macro-step end `index`, for the neighbours in this process (any thread).
  void publish(long index, double t);
  long published() const;
  // Bodies of the published end `index` packed into out, and its time.
  double pack_published(long index, const std::vector<int>& bodies, double* out) const;

  void save();               // x[0] and the integrator's step, to take a macro step again
  void restore(long index);  // back to the saved state; forgets the ends from `index` on

  long steps = 0, rejected = 0, evaluations = 0;

 private:
  struct Ghosted;  // the local system with extrapolated ghosts (loose_part.cpp)
  struct Sample {
    long index;
    double t;
    std::vector<double> bodies;  // packed, 13 numbers a ghost
  };
  struct Published {
    long index;
    double t;
    Eigen::VectorXd x;
  };
  // Exchange e's ghosts extrapolated to t, packed.
  void extrapolate(std::size_t e, double t, std::vector<double>& out) const;
  void extrapolate_ghosts(double t, Eigen::VectorXd& y);

  const RunOptions& o_;
  int order_;
  std::size_t retain_;
  std::vector<std::deque<Sample>> history_;    // per exchange, newest first
  std::vector<std::deque<Sample>> predicted_;  // per exchange, oldest first
  mutable std::mutex board_mutex_;
  std::deque<Published> board_;  // oldest first
  std::unique_ptr<Rk4> rk4_;
  std::unique_ptr<Dopri5> dopri5_;
  double h_ = 0.0;  // DOPRI5's next step
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

// Where the macro step from t with length H ends: at t + H, or on the next output time
// (grid.time of the output step, as the tight run has it) when it reaches that.
double next_macro_end(const StepGrid& grid, long output_every, long next_out, double t, double H, bool* on_output);

// The macro-step ends of a run with a fixed macro step H: ends[0] = t_start, and whether
// a snapshot is taken at each.
struct MacroGrid {
  std::vector<double> ends;
  std::vector<char> output;
  std::vector<long> tight_step;  // the tight grid's step at each end (rounded where between steps)
};
MacroGrid macro_grid(const RunOptions& o, double H);

// Macro steps per flow-graph run: up to the next snapshot, at most 64.
int steps_per_run(const MacroGrid& g);
// Walks the grid in runs of steps_per_run(g) at most that end at snapshots or earlier:
// run(m, n) takes macro steps m .. m + n - 1, and stops the walk when it returns false.
template <class Run>
void for_each_run(const MacroGrid& g, Run run) {
  const int most = steps_per_run(g);
  const auto total = static_cast<long>(g.ends.size()) - 1;
  for (long m = 0; m < total;) {
    int n = 1;
    while (m + n < total && !g.output[static_cast<std::size_t>(m + n)] && n < most) ++n;
    if (!run(m, n)) return;
    m += n;
  }
}

}  // namespace mbsflow::loose
