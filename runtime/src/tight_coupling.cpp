#include "tight_coupling.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "schedules.hpp"
#include "sink_runner.hpp"

namespace mbsflow {
namespace {

using partitioned::Part;

// A stage's work: skipped once the exchange stopped; a failure is handed to the exchange,
// which stops the stages still to come and rethrows it after the schedule's run.
template <class F>
void guarded(const TightRun& r, F f) {
  if (r.exchange.stopped()) return;
  try {
    if (r.clock)
      r.clock->time(f);
    else
      f();
  } catch (...) {
    r.exchange.fail(std::current_exception());
  }
}

// The schedule's proxy nodes for submodels elsewhere; key(c, s) is the exchange's step of
// stage input s of chunk step c, or nothing when that stage takes no values.
std::optional<RemoteInputs> proxies(const TightRun& r, std::function<std::optional<long>(int c, int s)> key) {
  const std::vector<char>* local = r.exchange.local_submodels();
  if (!local) return std::nullopt;
  RemoteInputs in;
  in.local = *local;
  in.wait = [&x = r.exchange, key = std::move(key)](int c, std::size_t q, std::size_t p, int s) {
    if (const auto n = key(c, s)) x.wait(*n, s, static_cast<int>(q), static_cast<int>(p));
  };
  return in;
}

TightCounts run_rk4(const TightRun& r) {
  const RunOptions& o = r.o;
  const StepGrid grid = step_grid(o.t_start, o.t_end, o.step);
  const int every = output_steps(o), chunk = chunk_length(every);
  long first = 0;
  const auto remote = proxies(r, [&](int c, int) { return std::optional<long>(first + c); });
  Scheduler schedule(
      r.d, chunk, 4,
      [&](std::size_t p, int s, int c, Half half) {
        guarded(r, [&] {
          const long n = first + c;
          Part& part = *r.parts[p];
          if (half == Half::inner) {  // needs no ghost values: runs while they travel
            partitioned::rk4_inner_stage(part, s, grid.time(n), grid.time(n + 1));
            return;
          }
          r.exchange.take(p, n, s);
          if (half == Half::whole)
            partitioned::rk4_stage(part, s, grid.time(n), grid.time(n + 1));
          else
            partitioned::rk4_edge_stage(part, s, grid.time(n), grid.time(n + 1));
          // The values this stage made: stage input s+1, or after the last stage the next step's state.
          const long n_next = s == 3 ? n + 1 : n;
          if (n_next < grid.steps) r.exchange.offer(p, n_next, (s + 1) % 4);
        });
      },
      r.barriers, remote ? &*remote : nullptr);
  step_in_chunks(
      grid, chunk, r.start ? r.start->steps : 0,
      [&](long from, int steps) {
        first = from;
        schedule.run(steps);
        r.exchange.check();
      },
      [&](long done) {
        r.output.step_done(done, grid.time(done), done % every == 0 || done == grid.steps ? done : -1);
        if (done < grid.steps && r.output.checkpoint_due()) {
          TightPoint point;
          point.steps = done;
          point.t = grid.time(done);
          r.output.checkpoint(point);
        }
      });
  return {grid.steps, 0, grid.steps * 4};
}

// The loop of run_simulation's DOPRI5 with the stages spread over submodels. Every
// process makes the same decisions: it sees the same error norm.
TightCounts run_dopri5(const TightRun& r) {
  const RunOptions& o = r.o;
  Dopri5Settings settings;
  settings.rtol = o.rtol;
  settings.atol = o.atol;
  dopri5::Controller control(settings);
  const StateLayout global = r.d.layout();
  Eigen::VectorXd squares = Eigen::VectorXd::Zero(global.size()), dense(global.size());
  double t = o.t_start, h = o.step;
  bool need_k0 = true;
  long attempt = 0;  // the exchange's step: attempts are numbered alike everywhere
  TightCounts counts;
  long next_out = 1;
  if (const TightPoint* p = r.start) {
    t = p->t;
    h = p->h;
    counts = {p->steps, p->rejected, p->evaluations};
    next_out = p->next_out;
    StateReader in(p->controller, "the DOPRI5 controller's state");
    control.restore(in);
  }
  const auto remote = proxies(r, [&](int, int s) {
    return s > 0 || need_k0 ? std::optional<long>(attempt) : std::nullopt;
  });
  Scheduler schedule(
      r.d, 1, 7,
      [&](std::size_t p, int s, int, Half half) {
        guarded(r, [&] {
          if (half == Half::inner) return;  // DOPRI5 stages are not split: the edge half does all
          if (s > 0 || need_k0) r.exchange.take(p, attempt, s);
          partitioned::dopri5_stage(*r.parts[p], s, t, h, need_k0, o.atol, o.rtol, squares);
          if (s < 6) r.exchange.offer(p, attempt, s + 1);
        });
      },
      r.barriers, remote ? &*remote : nullptr);
  while (t < o.t_end) {
    h = std::min(h, o.t_end - t);
    double taken = 0.0;
    // The schedule's stages read h: the step of the attempt.
    const bool ok = control.accepted_step(t, h, taken, counts.rejected, [&] {
      schedule.run(1);
      r.exchange.check();
      counts.evaluations += need_k0 ? 7 : 6;
      need_k0 = false;
      const double sum = r.exchange.error_sum(attempt, squares);
      ++attempt;
      return std::sqrt(sum / static_cast<double>(squares.size()));
    });
    if (!ok) throw RunError(step_collapsed_message(h, t, o.rtol));
    const double t_new = landed_time(t, taken, o.t_end);
    for (std::size_t p = 0; p < r.parts.size(); ++p)
      if (Part* part = r.parts[p]) {
        partitioned::dopri5_accept(*part, taken, t_new);  // element-wise, cheap
        if (t_new < o.t_end) r.exchange.offer(p, attempt, 0);
      }
    if (r.output.wants_dense())
      next_out = dense_outputs(o, next_out, t_new, [&](long k, double t_out) {
        for (const Part* part : r.parts)
          if (part) partitioned::dopri5_dense(*part, (t_out - t) / taken, dense);
        r.output.dense(k, t_out, dense);
      });
    ++counts.steps;
    t = t_new;
    need_k0 = true;
    r.output.step_done(counts.steps, t, t < o.t_end ? -1 : next_out);
    if (t < o.t_end && r.output.checkpoint_due()) {
      StateWriter w;
      control.save(w);
      r.output.checkpoint({counts.steps, counts.rejected, counts.evaluations, t, h, next_out, w.take()});
    }
  }
  return counts;
}

}  // namespace

int tight_stages(Method m) {
  if (const int stages = stepper_entry(m).tight_stages) return stages;
  // The methods with a stage scheme, from the registry: "RK4 or DOPRI5", "{method=rk4} or {method=dopri5}".
  const std::string upper = method_names(has_stage_scheme, "or", [](const char* name) {
    std::string u = name;
    for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return u;
  });
  const std::string settings =
      method_names(has_stage_scheme, "or", [](const char* name) { return "{method=" + std::string(name) + "}"; });
  throw InputError("a tightly coupled run of several submodels exchanges " + upper + " stages; " + method_name(m) +
                   " integrates a whole model (its stages run in parallel inside the step) or each submodel of a "
                   "loosely coupled run: give {coupling=loose}, or " + settings + ", or run it in one process on threads");
}

void save_tight_point(StateWriter& w, const TightPoint& p, const Eigen::VectorXd& y) {
  w.integer(p.steps);
  w.integer(p.rejected);
  w.integer(p.evaluations);
  w.real(p.t);
  w.real(p.h);
  w.integer(p.next_out);
  w.bytes(p.controller);
  w.vector(y);
}

TightPoint read_tight_point(StateReader& in, Eigen::Index size, Eigen::VectorXd& y) {
  TightPoint p;
  p.steps = in.integer(0, INT64_MAX);
  p.rejected = in.integer(0, INT64_MAX);
  p.evaluations = in.integer(0, INT64_MAX);
  p.t = in.real();
  p.h = in.real();
  p.next_out = in.integer(1, INT64_MAX);
  p.controller = in.bytes();
  y = in.vector(size);
  return p;
}

TightCounts run_tight_coupling(const TightRun& run) {
  return tight_stages(run.o.method) == 4 ? run_rk4(run) : run_dopri5(run);
}

}  // namespace mbsflow
