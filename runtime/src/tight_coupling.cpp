#include "tight_coupling.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "run_loop.hpp"
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

// RK4 in chunks of steps: a chunk's stages run through the flow graph, its snapshot (if
// one falls due) and checkpoint opportunity come after it.
class TightRk4 final : public Advancer {
 public:
  explicit TightRk4(const TightRun& r)
      : r_(r), grid_(step_grid(r.o.t_start, r.o.t_end, r.o.step)), every_(output_steps(r.o)), chunk_(chunk_length(every_)),
        done_(r.start ? r.start->steps : 0), remote_(proxies(r, [this](int c, int) { return std::optional<long>(first_ + c); })),
        schedule_(r.d, chunk_, 4, [this](std::size_t p, int s, int c, Half half) { stage(p, s, c, half); }, r.barriers,
                  remote_ ? &*remote_ : nullptr) {}

  bool done() const override { return done_ >= grid_.steps; }
  void advance(RunObserver& to) override {
    const int steps = static_cast<int>(std::min<long>(chunk_, grid_.steps - done_));
    first_ = done_;
    schedule_.run(steps);
    r_.exchange.check();
    done_ += steps;
    to.step_done(done_, grid_.time(done_), done_ % every_ == 0 || done_ == grid_.steps ? done_ : -1);
  }
  void save(StateWriter& w) override {
    TightPoint point;
    point.steps = done_;
    point.t = grid_.time(done_);
    save_tight_point(w, point);
  }
  TightCounts counts() const { return {grid_.steps, 0, grid_.steps * 4}; }

 private:
  void stage(std::size_t p, int s, int c, Half half) {
    guarded(r_, [&] {
      const long n = first_ + c;
      Part& part = *r_.parts[p];
      if (half == Half::inner) {  // needs no ghost values: runs while they travel
        partitioned::rk4_inner_stage(part, s, grid_.time(n), grid_.time(n + 1));
        return;
      }
      r_.exchange.take(p, n, s);
      if (half == Half::whole)
        partitioned::rk4_stage(part, s, grid_.time(n), grid_.time(n + 1));
      else
        partitioned::rk4_edge_stage(part, s, grid_.time(n), grid_.time(n + 1));
      // The values this stage made: stage input s+1, or after the last stage the next step's state.
      const long n_next = s == 3 ? n + 1 : n;
      if (n_next < grid_.steps) r_.exchange.offer(p, n_next, (s + 1) % 4);
    });
  }

  const TightRun& r_;
  StepGrid grid_;
  int every_, chunk_;
  long done_, first_ = 0;  // steps done; the first step of the chunk running
  std::optional<RemoteInputs> remote_;
  Scheduler schedule_;
};

// run_simulation's DOPRI5 with the stages spread over submodels, one accepted step per
// advance: the controller is the stepper's (dopri5::Controller). Every process makes the
// same decisions: it sees the same error norm.
class TightDopri5 final : public Advancer {
 public:
  explicit TightDopri5(const TightRun& r)
      : r_(r), o_(r.o), control_(settings(r.o)), squares_(Eigen::VectorXd::Zero(r.d.layout().size())),
        dense_(r.d.layout().size()), t_(o_.t_start), h_(o_.step),
        remote_(proxies(r, [this](int, int s) { return s > 0 || need_k0_ ? std::optional<long>(attempt_) : std::nullopt; })),
        schedule_(r.d, 1, 7, [this](std::size_t p, int s, int, Half half) { stage(p, s, half); }, r.barriers,
                  remote_ ? &*remote_ : nullptr) {
    if (const TightPoint* p = r.start) {
      t_ = p->t;
      h_ = p->h;
      counts_ = {p->steps, p->rejected, p->evaluations};
      next_out_ = p->next_out;
      StateReader in(p->controller, "the DOPRI5 controller's state");
      control_.restore(in);
    }
  }

  bool done() const override { return !(t_ < o_.t_end); }
  void advance(RunObserver& to) override {
    h_ = std::min(h_, o_.t_end - t_);
    double taken = 0.0;
    // The schedule's stages read h: the step of the attempt.
    const bool ok = control_.accepted_step(t_, h_, taken, counts_.rejected, [&] {
      schedule_.run(1);
      r_.exchange.check();
      counts_.evaluations += need_k0_ ? 7 : 6;
      need_k0_ = false;
      const double sum = r_.exchange.error_sum(attempt_, squares_);
      ++attempt_;
      return std::sqrt(sum / static_cast<double>(squares_.size()));
    });
    if (!ok) throw RunError(step_collapsed_message(h_, t_, o_.rtol));
    const double t_new = landed_time(t_, taken, o_.t_end);
    for (std::size_t p = 0; p < r_.parts.size(); ++p)
      if (Part* part = r_.parts[p]) {
        partitioned::dopri5_accept(*part, taken, t_new);  // element-wise, cheap
        if (t_new < o_.t_end) r_.exchange.offer(p, attempt_, 0);
      }
    if (to.wants_dense())
      next_out_ = dense_outputs(o_, next_out_, t_new, [&](long k, double t_out) {
        for (const Part* part : r_.parts)
          if (part) partitioned::dopri5_dense(*part, (t_out - t_) / taken, dense_);
        to.dense(k, t_out, dense_);
      });
    ++counts_.steps;
    t_ = t_new;
    need_k0_ = true;
    to.step_done(counts_.steps, t_, t_ < o_.t_end ? -1 : next_out_);
  }
  void save(StateWriter& w) override {
    StateWriter c;
    control_.save(c);
    save_tight_point(w, {counts_.steps, counts_.rejected, counts_.evaluations, t_, h_, next_out_, c.take()});
  }
  TightCounts counts() const { return counts_; }

 private:
  static Dopri5Settings settings(const RunOptions& o) {
    Dopri5Settings s;
    s.rtol = o.rtol;
    s.atol = o.atol;
    return s;
  }
  void stage(std::size_t p, int s, Half half) {
    guarded(r_, [&] {
      if (half == Half::inner) return;  // DOPRI5 stages are not split: the edge half does all
      if (s > 0 || need_k0_) r_.exchange.take(p, attempt_, s);
      partitioned::dopri5_stage(*r_.parts[p], s, t_, h_, need_k0_, o_.atol, o_.rtol, squares_);
      if (s < 6) r_.exchange.offer(p, attempt_, s + 1);
    });
  }

  const TightRun& r_;
  const RunOptions& o_;
  dopri5::Controller control_;
  Eigen::VectorXd squares_, dense_;
  double t_, h_;
  bool need_k0_ = true;
  long attempt_ = 0;  // the exchange's step: attempts are numbered alike everywhere
  TightCounts counts_;
  long next_out_ = 1;
  std::optional<RemoteInputs> remote_;
  Scheduler schedule_;
};

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

void save_tight_point(StateWriter& w, const TightPoint& p) {
  w.integer(p.steps);
  w.integer(p.rejected);
  w.integer(p.evaluations);
  w.real(p.t);
  w.real(p.h);
  w.integer(p.next_out);
  w.bytes(p.controller);
}

void save_tight_point(StateWriter& w, const TightPoint& p, const Eigen::VectorXd& y) {
  save_tight_point(w, p);
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
  // The state it starts from, for the neighbours' first stage: a ghost's own copy of it is
  // the model's, which its owner may have changed (a rigid cluster's initial velocities
  // projected onto its joints). A fixed-step run numbers steps from where it resumes; an
  // adaptive one its attempts from 0.
  const bool rk4 = tight_stages(run.o.method) == 4;
  const long first = rk4 && run.start ? run.start->steps : 0;
  for (std::size_t p = 0; p < run.parts.size(); ++p)
    if (run.parts[p]) run.exchange.offer(p, first, 0);
  if (rk4) {
    TightRk4 rk4(run);
    drive(rk4, run.output);
    return rk4.counts();
  }
  TightDopri5 dopri5(run);
  drive(dopri5, run.output);
  return dopri5.counts();
}

}  // namespace mbsflow
