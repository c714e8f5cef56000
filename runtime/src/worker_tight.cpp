// A worker's part of a tightly coupled run: RK4 with the boundary values exchanged at
// every stage, each stage an inner half (runs while they travel) and an edge half after
// the proxies (schedules.hpp, docs/cluster.md).
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <memory>

#include "schedules.hpp"
#include "sink_runner.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "worker_part.hpp"

namespace mbsflow {

using partitioned::Part;

Outcome run_tight(Session& s, WorkerIo& io, zmq::context_t& ctx, zmq::socket_t& inbox, const nlohmann::json& start,
                  int threads, const std::atomic<bool>* stop) {
  const std::size_t k = s.d.submodels.size();
  std::vector<std::unique_ptr<Part>> owned(k);
  std::vector<Part*> parts(k, nullptr);
  for (std::size_t q = 0; q < k; ++q)
    if (s.worker_of[q] == s.me) parts[q] = (owned[q] = std::make_unique<Part>(s.model, s.d.submodels[q], 4)).get();
  WorkerPart w(s, io, ctx, inbox, start, parts, stop);
  const StepGrid grid = step_grid(s.o.t_start, s.o.t_end, s.o.step);
  long first = 0;
  RemoteInputs remote;
  remote.local.assign(k, 0);
  for (int q : w.mine) remote.local[static_cast<std::size_t>(q)] = 1;
  remote.wait = [&](int c, std::size_t q, std::size_t p, int st) {
    w.exchange.wait(first + c, st, static_cast<int>(q), static_cast<int>(p));
  };
  const int chunk = chunk_length(output_steps(s.o));
  Scheduler schedule(
      s.d, chunk, 4,
      [&](std::size_t p, int st, int c, Half half) {
        if (w.exchange.aborted()) return;
        try {
          const long n = first + c;
          Part& part = *w.parts[p];
          if (half == Half::inner) {  // needs no ghost values: runs while they travel
            partitioned::rk4_inner_stage(part, st, grid.time(n), grid.time(n + 1));
            return;
          }
          for (const Submodel::Exchange& e : part.sub->exchanges)
            if (Part* owner = w.parts[static_cast<std::size_t>(e.neighbour)]) partitioned::copy_ghosts(*owner, e, part, st);
          w.exchange.receive(static_cast<int>(p), n, st);
          partitioned::rk4_edge_stage(part, st, grid.time(n), grid.time(n + 1));
          // The values this stage made: stage input st+1, or after the last stage the next step's state.
          const long n_next = st == 3 ? n + 1 : n;
          if (n_next < grid.steps) w.exchange.send(static_cast<int>(p), n_next, (st + 1) % 4);
        } catch (const std::exception& e) {
          w.exchange.abort(error_text(e));
        }
      },
      false, &remote);

  std::string failure;
  // A proxy waits on its thread (see RemoteInputs): one thread per local submodel at least.
  tbb::task_arena arena(std::max(threads > 0 ? threads : tbb::info::default_concurrency(), static_cast<int>(w.mine.size())));
  arena.execute([&] {
    step_in_chunks(
        grid, chunk, 0,
        [&](long from, int steps) {
          if (!failure.empty()) return;
          first = from;
          schedule.run(steps);
        },
        [&](long done) {
          if (!failure.empty()) return;
          failure = w.check(grid.time(done));
          if (failure.empty()) w.report_state(done, done % output_steps(s.o) == 0 || done == grid.steps);
        });
  });
  return w.finish(failure, failure.empty() ? grid.steps : first, 4.0 * static_cast<double>(grid.steps * static_cast<long>(w.mine.size())));
}

}  // namespace mbsflow
