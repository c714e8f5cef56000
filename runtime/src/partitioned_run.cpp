#include "mbsflow/runtime/partitioned_run.hpp"

#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <numeric>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/dopri5.hpp"
#include "partitioned_state.hpp"
#include "schedules.hpp"
#include "sink_runner.hpp"
#include "mbsflow/methods/step_grid.hpp"

namespace mbsflow {
namespace {

using Clock = std::chrono::steady_clock;
using partitioned::Part;

// Time spent in stage work, per thread.
class BusyClock {
 public:
  template <class F>
  void time(F f) {
    const auto start = Clock::now();
    f();
    busy_.local() += std::chrono::duration<double>(Clock::now() - start).count();
  }
  double total() const { return std::accumulate(busy_.begin(), busy_.end(), 0.0); }

 private:
  tbb::enumerable_thread_specific<double> busy_{0.0};
};

struct Context {
  const Model& model;
  const RunOptions& o;
  std::vector<Part>& parts;
  MultibodySystem& whole;
  ResultSink* sink;
  RunSummary& out;
  BusyClock& clock;
  Executor executor;
  const Decomposition& d;
};

void check_parts(const Context& c, double t) {
  if (auto dv = partitioned::check(c.parts)) throw RunError(divergence_message(c.model, *dv, t, c.o.method, c.o.step));
  check_stop(c.o, t);
}

void run_rk4(Context& c, Eigen::VectorXd& y) {
  const StepGrid grid = step_grid(c.o.t_start, c.o.t_end, c.o.step);
  long first = 0;
  Scheduler schedule(c.d, chunk_length(output_steps(c.o)), 4, [&](std::size_t p, int s, int step, Half) {
    c.clock.time([&] {
      partitioned::pull_ghosts(c.parts, p, s);
      const long n = first + step;
      partitioned::rk4_stage(c.parts[p], s, grid.time(n), grid.time(n + 1));
    });
  }, c.executor == Executor::barrier);
  step_in_chunks(
      grid, chunk_length(output_steps(c.o)), 0,
      [&](long from, int steps) {
        first = from;
        schedule.run(steps);
      },
      [&](long done) {
        const double t = grid.time(done);
        check_parts(c, t);
        if (c.sink && (done % output_steps(c.o) == 0 || done == grid.steps)) {
          partitioned::gather(c.parts, c.whole.layout(), y);
          emit(c.whole, c.sink, t, y, c.out);
        }
        if (c.o.progress) c.o.progress(t, done);
      });
  c.out.steps = grid.steps;
  c.out.evaluations = grid.steps * 4;
}

// The loop of run_simulation's DOPRI5, with the stages spread over submodels and the
// error norm the one global reduction per attempt.
void run_dopri5(Context& c, Eigen::VectorXd& y) {
  const RunOptions& o = c.o;
  Dopri5Settings settings;
  settings.rtol = o.rtol;
  settings.atol = o.atol;
  dopri5::Controller control(settings);
  Eigen::VectorXd squares(c.whole.dimension()), dense(c.whole.dimension());
  double t = o.t_start, h = o.step;
  bool need_k0 = true;
  Scheduler schedule(c.d, 1, 7, [&](std::size_t p, int s, int, Half) {
    c.clock.time([&] {
      if (s > 0 || need_k0) partitioned::pull_ghosts(c.parts, p, s);
      partitioned::dopri5_stage(c.parts[p], s, t, h, need_k0, o.atol, o.rtol, squares);
    });
  }, c.executor == Executor::barrier);
  const double dt_out = output_dt(o);
  long next_out = 1;
  while (t < o.t_end) {
    h = std::min(h, o.t_end - t);
    while (true) {  // attempts until one is accepted
      if (h < control.h_min(t)) throw RunError(step_collapsed_message(h, t, o.rtol));
      schedule.run(1);
      c.out.evaluations += need_k0 ? 7 : 6;
      need_k0 = false;
      const double err = std::sqrt(dopri5::ordered_sum(squares) / static_cast<double>(squares.size()));
      const dopri5::Controller::Decision decision = control.decide(err, h);
      if (decision.accept) {
        const double taken = h;
        const double t_new = landed_time(t, taken, o.t_end);
        for (Part& p : c.parts) partitioned::dopri5_accept(p, taken, t_new);  // element-wise, cheap
        while (c.sink) {
          const double t_out = o.t_start + static_cast<double>(next_out) * dt_out;
          if (t_out > t_new || t_out >= o.t_end) break;
          for (const Part& p : c.parts) partitioned::dopri5_dense(p, (t_out - t) / taken, dense);
          c.whole.after_step(t_out, dense);
          emit(c.whole, c.sink, t_out, dense, c.out);
          ++next_out;
        }
        ++c.out.steps;
        t = t_new;
        h = decision.h;
        need_k0 = true;
        break;
      }
      ++c.out.rejected;
      h = decision.h;
    }
    check_parts(c, t);
    if (o.progress) o.progress(t, c.out.steps);
  }
  if (c.sink) {
    partitioned::gather(c.parts, c.whole.layout(), y);
    emit(c.whole, c.sink, t, y, c.out);
  }
}

}  // namespace

int default_partitions(const Model& model, int threads) {
  return std::max(1, std::min(threads, static_cast<int>(model.bodies.size() / 64)));
}

RunSummary run_partitioned(const Model& model, const Decomposition& d, const RunOptions& o, const ParallelOptions& par,
                           ResultSink* sink, ParallelStats* stats) {
  check_options(o);
  stepper_entry(o.method);  // a method that exists
  if (!(o.method == Method::rk4 || o.method == Method::dopri5))
    throw InputError(std::string("a tightly coupled run of several submodels exchanges RK4 or DOPRI5 stages; ") +
                     method_name(o.method) +
                     " integrates a whole model (its stages run in parallel inside the step) or each submodel of a "
                     "loosely coupled run");
  const int threads = par.threads > 0 ? par.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  RunSummary out;
  BusyClock clock;
  const int stages = o.method == Method::rk4 ? 4 : 7;
  std::vector<Part> parts;
  parts.reserve(d.submodels.size());
  for (const Submodel& s : d.submodels) parts.emplace_back(model, s, stages);
  MultibodySystem whole(model);  // for the sink: layout, names, energies
  // Like run_simulation, which gets its system built: the clock starts with the run.
  const auto start = Clock::now();
  Eigen::VectorXd y = whole.initial_state();
  if (sink) sink->begin(whole);
  Context c{model, o, parts, whole, sink, out, clock, par.executor, d};
  run_with_sink(sink, out, [&] {
    if (sink) emit(whole, sink, o.t_start, y, out);
    arena.execute([&] {
      if (o.method == Method::rk4)
        run_rk4(c, y);
      else
        run_dopri5(c, y);
    });
  });
  partitioned::gather(parts, whole.layout(), y);
  out.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  out.final_state = std::move(y);
  if (stats) {
    stats->threads = threads;
    stats->busy_seconds = clock.total();
    stats->wait_fraction = std::max(0.0, 1.0 - stats->busy_seconds / (out.wall_seconds * threads));
  }
  return out;
}

}  // namespace mbsflow
