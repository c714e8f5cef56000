#include "mbsflow/runtime/partitioned_run.hpp"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_group.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>

#include "mbsflow/error.hpp"
#include "partitioned_state.hpp"
#include "run_loop.hpp"
#include "tsan_annotations.hpp"
#include "tight_coupling.hpp"

namespace mbsflow {
namespace {

// Tokens of the parallel build of a run's parts (for ThreadSanitizer; see run_partitioned).
const char build_start = 0, build_done = 0;

using Clock = std::chrono::steady_clock;
using partitioned::Part;

}  // namespace

int default_partitions(const Model& model, int threads) {
  const int k = std::max(1, std::min(threads, static_cast<int>(model.bodies.size() / 64)));
  if (k == 1) return 1;
  const std::vector<int> piece = uncut_pieces(model);  // never more submodels than pieces
  return std::min(k, *std::max_element(piece.begin(), piece.end()) + 1);
}

RunSummary run_partitioned(const Model& model, const Decomposition& d, const RunOptions& o, const ParallelOptions& par,
                           ResultSink* sink, ParallelStats* stats) {
  return run_partitioned(std::make_shared<const Model>(model), d, o, par, sink, stats);
}

RunSummary run_partitioned(std::shared_ptr<const Model> shared, const Decomposition& d, const RunOptions& o,
                           const ParallelOptions& par, ResultSink* sink, ParallelStats* stats) {
  const Model& model = *shared;
  check_options(o);
  stepper_entry(o.method);  // a method that exists
  const int stages = tight_stages(o.method);
  const int threads = par.threads > 0 ? par.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  BusyClock clock;
  // The parts and the whole system (for the sink: layout, names, energies, and for
  // checkpoints; it shares the model) are built side by side: each is a pass over its
  // bodies and joints, and a million-body model's take seconds each. A run with neither
  // results nor checkpoints builds no whole system (a chain's is 300 bytes per body).
  const bool need_whole = sink != nullptr || o.checkpoint != nullptr;
  std::vector<std::optional<Part>> built(d.submodels.size());
  std::optional<MultibodySystem> built_whole;
  {
    // ThreadSanitizer does not see oneTBB's orderings (tsan_annotations.hpp): the tasks
    // state that they see what this thread wrote before (a token at namespace scope, taken
    // before any capture is read), and this thread that it sees what they built, also where
    // one threw. The tasks are made (their captures copied into them) before the token is
    // released, and run after: a task made by run() could start before this thread could
    // release anything after its captures. The group lives on the heap: its completion
    // count, which the tasks update after their last statement, would otherwise share
    // stack addresses with what this thread writes next.
    auto group = std::make_unique<tbb::task_group>();  // made before the token: the tasks update it
    const AcquireOnExit built_seen{&build_done};  // also where a task threw
    arena.execute([&] {
      std::vector<tbb::task_handle> tasks;
      for (std::size_t i = 0; i < built.size(); ++i)
        tasks.push_back(group->defer([&, i] {
          happens_after(&build_start);
          const ReleaseOnExit done{&build_done};
          built[i].emplace(model, d.submodels[i], stages, true);
        }));
      if (need_whole)
        tasks.push_back(group->defer([&] {
          happens_after(&build_start);
          const ReleaseOnExit done{&build_done};
          built_whole.emplace(std::move(shared), static_cast<int>(model.bodies.size()));
        }));
      happens_before(&build_start);
      for (tbb::task_handle& t : tasks) group->run(std::move(t));
      group->wait();
    });
  }
  std::vector<Part> parts;
  parts.reserve(built.size());
  for (std::optional<Part>& p : built) parts.push_back(std::move(*p));
  built.clear();
  MultibodySystem* whole = built_whole ? &*built_whole : nullptr;
  const StateLayout global = d.layout();
  phase_done(o, whole ? "build the submodels and the whole system" : "build the submodels");
  // Like run_simulation, which gets its system built: the clock starts with the run.
  const auto start = Clock::now();
  // The gathered state, for the sink and checkpoints (then whole is built), and at the end.
  Eigen::VectorXd y = whole ? whole->initial_state() : Eigen::VectorXd();
  std::optional<TightPoint> resumed;
  LocalRun run("tight", o, whole, sink,
                {.check = [&](double t) {
                   if (auto dv = partitioned::check(parts)) throw RunError(divergence_message(model, *dv, t, o.method, o.step));
                 },
                 .state = [&](Eigen::VectorXd& x) { partitioned::gather(parts, whole->layout(), x); },
                 .restore = [&](StateReader& in) {  // where the loop is, and the parts' x[0] set
                   resumed = read_tight_point(in, whole->dimension(), y);
                   for (Part& part : parts) partitioned::scatter(y, whole->layout(), part);
                   return resumed->t;
                 },
                 .save_state = [&](StateWriter& w) {  // the state whatever the partition: the global state
                   Eigen::VectorXd x;  // for this checkpoint only: not held through the run
                   partitioned::gather(parts, whole->layout(), x);
                   w.vector(x);
                 }});
  run.begin();
  std::vector<Part*> local;
  for (Part& p : parts) local.push_back(&p);
  LocalExchange exchange(local);
  RunSummary& out = run.out;
  run.run([&] { return std::move(y); },  // gathered again when needed
          [&] {
            arena.execute([&] {
              const TightCounts counts = run_tight_coupling(
                  {d, local, o, exchange, run, par.executor == Executor::barrier, &clock, resumed ? &*resumed : nullptr});
              out.steps = counts.steps;
              out.rejected = counts.rejected;
              out.evaluations = counts.evaluations;
            });
          });
  phase_done(o, sink ? "steps, and the results written" : "steps", RunPhase::steps);
  // The stage vectors go before the final state is gathered, which then takes their place
  // rather than adding to the peak (a million bodies' state is 104 MB).
  for (Part& p : parts) {
    p.x.resize(1);
    p.k = {};
    p.r = {};
  }
  partitioned::gather(parts, global, y);
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  if (stats) {
    stats->threads = threads;
    stats->busy_seconds = clock.total();
    stats->wait_fraction = std::max(0.0, 1.0 - stats->busy_seconds / (out.wall_seconds * threads));
  }
  return std::move(out);
}

}  // namespace mbsflow
