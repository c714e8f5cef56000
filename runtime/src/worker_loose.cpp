// A worker's part of a loosely coupled run: its submodels integrate macro steps on their
// own (loose_rounds.hpp) and exchange their boundary bodies with the other workers at the
// macro-step ends only. Without a lag (or with an exact one) every worker takes the same
// macro steps and neighbour values as the one-process run_loose, so the results are the
// same to the bit; with a lag, each takes the newest values that have arrived.
#include <memory>

#include "loose_part.hpp"
#include "mbsflow/error.hpp"
#include "loose_advancer.hpp"
#include "loose_rounds.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "worker_part.hpp"

namespace mbsflow {

using loose::LoosePart;

namespace {

// The starting past j (1..k, stage input j of step 0) of the local submodels to their
// remote neighbours, and theirs into the ghost slots of x[j]. False if the exchange stopped.
bool exchange_past(WorkerPart& w, std::vector<std::unique_ptr<LoosePart>>& lp, int j) {
  for (int p : w.mine) w.exchange.send(p, 0, j);
  loose::copy_local_ghosts(lp, j);
  for (int p : w.mine) {
    for (const Submodel::Exchange& e : lp[static_cast<std::size_t>(p)]->part.sub->exchanges)
      if (!lp[static_cast<std::size_t>(e.neighbour)]) w.exchange.wait(0, j, e.neighbour, p);
    if (w.exchange.aborted()) return false;
    w.exchange.receive(p, 0, j);
  }
  return !w.exchange.aborted();
}

// The results to the coordinator: the coupling records and snapshots at each macro-step
// end, its progress on the tight grid, checkpoints with the time first (the coordinator
// checks that every worker sent the same). A stop is thrown.
class LooseCoordinatorOutput final : public RunObserver {
 public:
  LooseCoordinatorOutput(WorkerPart& w, loose::LooseRounds& rounds, const loose::MacroGrid& grid)
      : w_(w), rounds_(rounds), grid_(grid), tight_(step_grid(w.s.o.t_start, w.s.o.t_end, w.s.o.step)) {}
  void reached(double t) override {
    if (const std::string why = w_.check(t); !why.empty()) throw RunError(why);
    t_ = t;
    report_coupling();
  }
  void dense(long index, double t, Eigen::VectorXd& y, bool projected) override {
    w_.report_dense(grid_.output_step(index), t, index, y, !projected);
  }
  void step_done(long m, double, long) override {
    const long step = grid_.tight_step(m);
    w_.report_state(step, tight_.time(step), -1);
  }
  bool checkpoint_due() override { return w_.checkpoint_due(); }
  void checkpoint(const std::function<void(StateWriter&)>& save) override {
    StateWriter out;
    out.real(t_);
    save(out);
    w_.send_checkpoint(out.take());
  }
  // The records since the last report.
  void report_coupling() {
    loose::CouplingLog batch;
    rounds_.drain(batch);
    w_.report_coupling(batch.records());
  }

 private:
  WorkerPart& w_;
  loose::LooseRounds& rounds_;
  const loose::MacroGrid& grid_;
  StepGrid tight_;  // the coordinator's snapshot times
  double t_ = 0.0;
};

}  // namespace

Outcome run_loose_part(Session& s, WorkerTransport& transport, const nlohmann::json& start, int threads,
                       const std::atomic<bool>* stop) {
  LooseOptions lo = *s.loose;
  lo.threads = threads;
  s.d = loose_decomposition(s.model, s.d, lo);  // the same overlap in every worker
  const std::size_t k = s.d.submodels.size();
  std::vector<std::unique_ptr<LoosePart>> lp(k);
  std::vector<partitioned::Part*> parts(k, nullptr);
  for (std::size_t q = 0; q < k; ++q)
    if (s.worker_of[q] == s.me) parts[q] = &(lp[q] = loose::make_part(s.model, s.d.submodels[q], s.o, lo, q))->part;
  WorkerPart w(s, transport, start, parts, 4, stop);
  w.exchange.start_at(0);
  loose::MacroGrid grid(s.o, lo.coupling_tol > 0.0 ? 0.0 : lo.macro_step);
  loose::RemoteSamples remote;
  remote.wait = [&](long index, int q, int p) { w.exchange.wait(index, 0, q, p); };
  remote.take = [&](int p, int q, long cap, const std::function<void(long, const double*)>& take) {
    w.exchange.take_upto(p, q, 0, cap, take);
  };
  remote.send = [&](int p, long index) { w.exchange.send(p, index, 0); };
  remote.stopped = [&] { return w.exchange.aborted(); };
  remote.abort = [&](const std::string& why) { w.exchange.abort(why); };
  loose::LooseRounds rounds(s.model, s.d, s.o, lo, lp, grid, grid.steps_per_run(), &remote);
  LooseStats st;
  const StateLayout global = s.d.layout();
  // Every worker takes the same adaptive macro steps: the largest error over all decides.
  loose::LooseAdvancer advancer(s.o, lo, lp, rounds, grid, st, global, Eigen::VectorXd::Zero(global.size()),
                                {[&](long attempt, double e) { return w.exchange.max_over_workers(attempt, e); },
                                 [&](long index) { w.exchange.rewind(0, index); }});
  LooseCoordinatorOutput output(w, rounds, grid);

  std::string failure;
  if (!s.resume.empty()) {
    // The coordinator's checkpoint: this worker's position and submodels. The ends they
    // published that a remote neighbour may not have taken yet go out again (a neighbour
    // takes each end once, so those it had are dropped).
    try {
      StateReader in(s.resume, "the coordinator's checkpoint");
      (void)in.real();  // its time, for the coordinator
      advancer.restore(in);
      if (!in.at_end()) in.fail("it holds more than this worker's state");
    } catch (const std::exception& e) {
      failure = error_text(e);
    }
    if (failure.empty())
      for (int p : w.mine)
        lp[static_cast<std::size_t>(p)]->each_published([&](long index, const Eigen::VectorXd& x) { w.exchange.send(p, index, 0, x); });
  } else {
    for (int p : w.mine) lp[static_cast<std::size_t>(p)]->make_past(s.o.t_start, lo.macro_step);
    for (int j = 1; j <= lo.extrapolation && failure.empty(); ++j)
      if (!exchange_past(w, lp, j)) failure = w.exchange.why();
    for (int p : w.mine) lp[static_cast<std::size_t>(p)]->start(s.o.t_start, lo.macro_step);
  }
  if (failure.empty()) {
    try {
      drive(advancer, output);
    } catch (const std::exception& e) {
      failure = error_text(e);
    }
  }
  const long done = advancer.at.done;
  if (failure.empty()) {
    rounds.catch_up(done);  // the coupling errors of the last macro steps
    failure = w.check(grid.end(done));
    output.report_coupling();
  }
  double evaluations = 0.0;
  for (int p : w.mine) evaluations += static_cast<double>(lp[static_cast<std::size_t>(p)]->evaluations);
  return w.finish(failure, grid.tight_step(done), grid.end(done), evaluations);
}

}  // namespace mbsflow
