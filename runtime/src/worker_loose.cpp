// A worker's part of a loosely coupled run: its submodels integrate macro steps on their
// own (loose_part.hpp) and exchange their boundary bodies with the other workers at the
// macro-step ends only. Every worker takes the same macro steps and ghost values as the
// one-process run_loose, so the results are the same to the bit.
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <memory>

#include "loose_part.hpp"
#include "schedules.hpp"
#include "step_grid.hpp"
#include "worker_part.hpp"

namespace mbsflow {

using loose::LoosePart;

namespace {

// Ghost slots of x[j] from the owners' values: local owners' through from(owner) (their
// x[j], or what they kept), remote ones' from message n in the inbox. False if the
// exchange was stopped.
template <class From>
bool receive_values(WorkerPart& w, std::vector<std::unique_ptr<LoosePart>>& lp, long n, int j, From from) {
  loose::copy_local_ghosts(lp, j, from);
  for (int p : w.mine) {
    for (const Submodel::Exchange& e : lp[static_cast<std::size_t>(p)]->part.sub->exchanges)
      if (!lp[static_cast<std::size_t>(e.neighbour)]) w.exchange.wait(n, j, e.neighbour, p);
    if (w.exchange.aborted()) return false;
    w.exchange.receive(p, n, j);
  }
  return !w.exchange.aborted();
}

}  // namespace

Outcome run_loose_part(Session& s, WorkerIo& io, zmq::context_t& ctx, zmq::socket_t& inbox, const nlohmann::json& start,
                       int threads, const std::atomic<bool>* stop) {
  const LooseOptions& lo = *s.loose;
  const std::size_t k = s.d.submodels.size();
  std::vector<std::unique_ptr<LoosePart>> lp(k);
  std::vector<partitioned::Part*> parts(k, nullptr);
  for (std::size_t q = 0; q < k; ++q)
    if (s.worker_of[q] == s.me) parts[q] = &(lp[q] = std::make_unique<LoosePart>(s.model, s.d.submodels[q], s.o, lo.extrapolation, lo.max_lag))->part;
  WorkerPart w(s, io, ctx, inbox, start, parts, stop);
  const StepGrid grid = step_grid(s.o.t_start, s.o.t_end, s.o.step);
  double t0 = 0.0, t1 = 0.0;
  // One node per local submodel per macro step, all independent within the step.
  Scheduler schedule(s.d, 1, 1, [&](std::size_t p, int, int, Half) {
    if (lp[p] && !w.exchange.aborted()) {
      try {
        lp[p]->integrate(t0, t1);
      } catch (const std::exception& e) {
        w.exchange.abort(e.what());
      }
    }
  });
  tbb::task_arena arena(threads > 0 ? threads : tbb::info::default_concurrency());
  // Messages: the starting past j (1..k) as message j, the macro-step ends from k+1 on.
  std::string failure;
  long step = 0;  // of the tight grid, for the coordinator
  for (int p : w.mine) lp[static_cast<std::size_t>(p)]->make_past(s.o.t_start, lo.macro_step);
  for (int j = 1; j <= lo.extrapolation && failure.empty(); ++j) {
    for (int p : w.mine) w.exchange.send(p, j, j);
    if (!receive_values(w, lp, j, j, [j](const LoosePart& owner) -> const Eigen::VectorXd& {
          return owner.part.x[static_cast<std::size_t>(j)];
        }))
      failure = w.exchange.why();
  }
  for (int p : w.mine) lp[static_cast<std::size_t>(p)]->start(s.o.t_start, lo.macro_step);
  double t = s.o.t_start;
  long next_out = 1, index = 0;  // macro-step ends so far; the end i is message extrapolation + i
  while (failure.empty() && t < s.o.t_end) {
    bool on_output = false;
    t0 = t;
    t1 = loose::next_macro_end(grid, s.o.output_every, next_out, t, lo.macro_step, &on_output);
    arena.execute([&] { schedule.run(1); });
    failure = w.check(t1);
    if (!failure.empty()) break;
    ++index;
    for (int p : w.mine) {
      lp[static_cast<std::size_t>(p)]->keep(index, t1);
      w.exchange.send(p, lo.extrapolation + index, 0);
    }
    // The neighbours' values at the macro-step end max_lag steps back (this one for 0).
    const long lagged = index - lo.max_lag;
    if (lagged >= 1) {
      if (!receive_values(w, lp, lo.extrapolation + lagged, 0,
                          [lagged](const LoosePart& owner) -> const Eigen::VectorXd& { return owner.kept(lagged); })) {
        failure = w.exchange.why();
        break;
      }
      for (int p : w.mine) lp[static_cast<std::size_t>(p)]->push(lp[static_cast<std::size_t>(p)]->kept_time(lagged));
    }
    t = t1;
    step = on_output ? std::min(next_out * static_cast<long>(s.o.output_every), grid.steps)
                     : std::lround((t - s.o.t_start) / s.o.step);
    w.report_state(step, on_output);
    if (on_output) ++next_out;
  }
  double evaluations = 0.0;
  for (int p : w.mine) evaluations += static_cast<double>(lp[static_cast<std::size_t>(p)]->evaluations);
  return w.finish(failure, failure.empty() ? grid.steps : step, evaluations);
}

}  // namespace mbsflow
