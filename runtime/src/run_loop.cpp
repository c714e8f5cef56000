#include "run_loop.hpp"

#include "sink_runner.hpp"

namespace mbsflow {

void drive(Advancer& a, RunObserver& to) {
  while (!a.done()) {
    a.advance(to);
    if (!a.done() && to.checkpoint_due()) to.checkpoint([&a](StateWriter& w) { a.save(w); });
  }
}

LocalRun::LocalRun(const char* kind, const RunOptions& o, MultibodySystem* whole, ResultSink* sink, Hooks hooks)
    : kind_(kind), o_(o), whole_(whole), sink_(sink), hooks_(std::move(hooks)), timer_(o.checkpoint) {}

void LocalRun::begin() {
  if (resuming()) {
    const Checkpointing& c = *o_.checkpoint;
    StateReader in(c.resume, c.resume_from);
    const std::string results = read_checkpoint_head(in, kind_, o_.method, out);
    out.resumed_at = hooks_.restore(in);
    resume_results(in, c, sink_, *whole_, results, out);
  } else if (sink_) {
    sink_->begin(*whole_);
  }
  if (sink_) phase_done(o_, "start the results file");
}

void LocalRun::run(const std::function<Eigen::VectorXd()>& first, const std::function<void()>& body,
                   const std::function<void()>& before_end) {
  run_with_sink(
      sink_, out,
      [&] {
        if (sink_ && !resuming()) {
          sink_->make_room();  // before the first state is made: it moves into the snapshot
          emit(*whole_, sink_, o_.t_start, first(), out);
        }
        body();
      },
      before_end);
}

void LocalRun::step_done(long steps, double t, long snapshot) {
  if (hooks_.check) hooks_.check(t);
  check_stop(o_, t);
  if (sink_ && snapshot >= 0) {
    sink_->make_room();  // before the state is gathered: it moves into the snapshot
    hooks_.state(y_);
    emit(*whole_, sink_, t, std::move(y_), out);
  }
  if (o_.progress && steps % hooks_.progress_every == 0) o_.progress(t, steps);
}

void LocalRun::dense(long, double t, Eigen::VectorXd& y, bool projected) {
  emit(*whole_, sink_, t, y, out, projected);
}

void LocalRun::checkpoint(const std::function<void(StateWriter&)>& save) {
  StateWriter w = checkpoint_head(kind_, o_.method, sink_, out);
  save(w);
  if (hooks_.save_state) hooks_.save_state(w);
  o_.checkpoint->write(w.take());
}

}  // namespace mbsflow
