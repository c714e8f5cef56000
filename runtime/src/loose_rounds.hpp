#pragma once
// The macro steps of a loosely coupled run as a oneTBB flow graph, shared by the one-process
// run and the workers: node (m, p) integrates submodel p from macro-step end m to m + 1.
// It first takes the neighbours' values it has: every end up to m (the newest), or with an
// exact lag exactly up to m - L. It waits for end m - L at least: for a neighbour here,
// through a graph edge from that neighbour's node (m - 1 - L); for one in another process,
// through a proxy node that waits for its message. So a submodel runs up to L macro steps
// ahead of its slowest neighbour, and with L = 0 (or an exact lag) the numbers do not
// depend on timing. Each neighbour value taken is compared with what the submodel had
// extrapolated for it: the coupling error, recorded per macro-step end.
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "coupling_log.hpp"
#include "mbsflow/error.hpp"
#include "loose_part.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "schedules.hpp"

namespace mbsflow::loose {

// Submodel q's part with its method and as many published ends kept as a neighbour up to
// L macro steps behind may still take (2 L + 3).
std::unique_ptr<LoosePart> make_part(const Model& model, const Submodel& sub, const RunOptions& o, const LooseOptions& lo,
                                     std::size_t q);

// Macro-step ends to keep behind the run: a neighbour's value may be taken up to 2 L + 3
// macro steps late.
inline long ends_kept(const LooseOptions& lo) { return 2L * lo.max_lag + 8; }

// Neighbours in other processes (a worker's run).
struct RemoteSamples {
  // Returns once remote q's macro-step end `index` for local p is in, or the exchange stopped.
  std::function<void(long index, int q, int p)> wait;
  // Remote q's ends for local p with index <= cap that are in, oldest first, to take(index, packed).
  std::function<void(int p, int q, long cap, const std::function<void(long, const double*)>& take)> take;
  // Local p's state as macro-step end `index`, to the remote submodels that need it.
  std::function<void(int p, long index)> send;
  std::function<bool()> stopped;
  std::function<void(const std::string&)> abort;
};

class LooseRounds {
 public:
  // parts[q]: local submodel q, null where it runs elsewhere (then remote is needed).
  // grid: the macro-step ends (the caller may change it between runs).
  LooseRounds(const Model& model, const Decomposition& d, const RunOptions& o, const LooseOptions& lo,
              std::vector<std::unique_ptr<LoosePart>>& parts, const MacroGrid& grid, int chunk,
              RemoteSamples* remote = nullptr);
  ~LooseRounds();

  // Macro steps first .. first + n - 1 (n <= chunk). A failure message, empty if none.
  std::string run(long first, int n);
  // Whether the submodels keep the snapshots that fall in their macro steps (none are
  // wanted when nothing takes the results).
  bool keep_snapshots = true;
  // Takes every neighbour value up to end `index` (waiting for remote ones).
  void catch_up(long index);
  // The largest coupling error of this process's submodels at end `index` (after catch_up).
  CouplingError worst(long index) const;
  // The records since the last call, into log; discard(index) forgets those from
  // macro-step end `index` on (a macro step to be taken again).
  void drain(CouplingLog& log);
  void discard(long index);

 private:
  void step(std::size_t p, long m);
  void pull(std::size_t p, long cap);
  void fail(const std::string& why);
  bool stopped() const;

  const Model& model_;
  const RunOptions& o_;
  int lag_;
  double reach_;  // the overlap's
  bool exact_;
  std::vector<std::unique_ptr<LoosePart>>& parts_;
  const MacroGrid& grid_;
  RemoteSamples* remote_;
  std::vector<std::vector<CouplingRecord>> logs_;  // per submodel, written by its nodes only
  std::vector<std::vector<double>> scratch_;       // per submodel
  long first_ = 0;
  std::atomic<bool> failed_{false};
  std::mutex failure_mutex_;
  std::string failure_;
  RemoteInputs inputs_;
  tbb::task_arena arena_;
  std::unique_ptr<Scheduler> schedule_;  // built in the arena; goes before it
};

// Where a walk of adaptive macro steps is: macro steps taken, tries so far, the time
// reached and the next macro step. A checkpoint keeps it.
struct AdaptiveWalk {
  long m = 0, attempt = 0;
  double t = 0.0, H = 0.0;
};

inline AdaptiveWalk adaptive_start(const RunOptions& o, const LooseOptions& lo) { return {0, 0, o.t_start, lo.macro_step}; }

// Where a loose run's loop is (in one process or a worker): macro steps done, the next
// snapshot, the adaptive walk. A checkpoint keeps it with the macro-step ends.
struct LoosePosition {
  long done = 0, next_output = 1;
  AdaptiveWalk walk;
};

inline void save_position(StateWriter& w, const LoosePosition& p, const MacroGrid& grid) {
  w.integer(p.done);
  w.integer(p.next_output);
  w.integer(p.walk.m);
  w.integer(p.walk.attempt);
  w.real(p.walk.t);
  w.real(p.walk.H);
  grid.save(w);
}

inline void restore_position(StateReader& in, LoosePosition& p, MacroGrid& grid) {
  p.done = in.integer(0, INT64_MAX / 2);
  p.next_output = in.integer(1, INT64_MAX / 2);
  p.walk.m = in.integer(0, INT64_MAX / 2);
  p.walk.attempt = in.integer(0, INT64_MAX / 2);
  p.walk.t = in.real();
  p.walk.H = in.real();
  grid.restore(in);
}

}  // namespace mbsflow::loose
