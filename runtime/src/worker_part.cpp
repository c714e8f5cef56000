#include "worker_part.hpp"

#include <cstdio>
#include <thread>

#include "mbsflow/runtime/divergence.hpp"

namespace mbsflow {

using nlohmann::json;

WorkerPart::WorkerPart(Session& session, WorkerTransport& transport, const json& start, std::vector<partitioned::Part*> local,
                       int stages, const std::atomic<bool>* stop)
    : s(session), parts(std::move(local)), exchange_(transport.exchange(s, start, parts, stages)), exchange(*exchange_),
      control_(transport.control()), results_(transport.results(s)), stop_(stop) {
  for (std::size_t q = 0; q < parts.size(); ++q)
    if (parts[q]) {
      mine.push_back(static_cast<int>(q));
      share_.add(s.d, *parts[q]->sub);
    }
  control_.attach(&exchange);
  control_.progress_clock()->store(wire::now_ns());
}

WorkerPart::~WorkerPart() { control_.attach(nullptr); }

void WorkerPart::report(wire::ResultKind kind, long steps, double t, long index, const void* data, std::size_t bytes) {
  wire::ResultHeader h;
  h.kind = kind;
  h.worker = s.me;
  h.step = steps;
  h.index = index;
  h.t = t;
  h.run = s.run;
  if (!results_->send(h, data, bytes)) exchange.abort("the coordinator stopped taking results");
}

std::string WorkerPart::check(double t) const {
  if (s.hang_after_s >= 0.0 && wire::seconds_since(started_) > s.hang_after_s)
    while (!exchange.aborted()) std::this_thread::yield();  // tests: a step that never ends
  control_.progress_clock()->store(wire::now_ns());
  if (exchange.aborted()) return exchange.why();
  for (int q : mine)
    if (auto dv = partitioned::check(*parts[static_cast<std::size_t>(q)]))
      return divergence_message(s.model, *dv, t, s.o.method, s.o.step);
  if (stop_ && stop_->load()) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "the worker was interrupted at t = %.6g s", t);
    return buf;
  }
  return "";
}

void WorkerPart::pack_own(std::vector<double>& out) const {
  out.clear();
  out.reserve(share_.numbers());
  for (int q : mine) {  // share_'s order: the bodies, then the modes
    const partitioned::Part& part = *parts[static_cast<std::size_t>(q)];
    const std::size_t at = out.size();
    out.resize(at + static_cast<std::size_t>(part.own) * partitioned::body_numbers);
    partitioned::pack_bodies(part.system.layout(), part.x[0], part.own_bodies, out.data() + at);
  }
  for (int q : mine) {
    const partitioned::Part& part = *parts[static_cast<std::size_t>(q)];
    for (const partitioned::Part::Tail& t : part.tails)
      out.insert(out.end(), part.x[0].data() + t.local, part.x[0].data() + t.local + t.size);
  }
}

void WorkerPart::report_state(long steps, double t, long snapshot) {
  if (snapshot < 0) return report(wire::ResultKind::progress, steps, t, 0, nullptr, 0);
  pack_own(snapshot_);
  report(wire::ResultKind::snapshot, steps, t, snapshot, snapshot_.data(), snapshot_.size() * sizeof(double));
}

void WorkerPart::report_dense(long steps, double t, long index, const Eigen::VectorXd& y, bool project) {
  snapshot_.resize(share_.numbers());
  partitioned::pack_share(s.d.layout(), y, share_, snapshot_.data());
  report(project ? wire::ResultKind::dense : wire::ResultKind::snapshot, steps, t, index, snapshot_.data(),
         snapshot_.size() * sizeof(double));
}

void WorkerPart::report_coupling(const std::vector<CouplingRecord>& records) {
  if (records.empty()) return;
  std::vector<double> rows;
  for (const CouplingRecord& r : records)
    rows.insert(rows.end(), {static_cast<double>(r.index), r.t_start, r.t_end, r.position_error, r.velocity_error,
                             static_cast<double>(r.lag)});
  report(wire::ResultKind::coupling, 0, records.back().t_end, 0, rows.data(), rows.size() * sizeof(double));
}

bool WorkerPart::checkpoint_due() {
  ++opportunity_;
  const std::int64_t asked = control_.checkpoint_request();
  if (asked < 0 || asked == answered_ || asked > opportunity_) return false;
  answered_ = asked;
  if (asked == opportunity_) return true;
  report(wire::ResultKind::checkpoint, asked, 0.0, opportunity_, nullptr, 0);  // missed: past it
  return false;
}

void WorkerPart::send_checkpoint(const std::vector<std::uint8_t>& state) {
  report(wire::ResultKind::checkpoint, answered_, 0.0, opportunity_, state.data(), state.size());
}

Outcome WorkerPart::finish(std::string failure, long steps, double t, double evaluations, long rejected) {
  if (failure.empty() && exchange.aborted()) failure = exchange.why();
  const double counts[wire::done_counts] = {static_cast<double>(exchange.messages_sent()), exchange.bytes_per_stage(),
                                            evaluations, static_cast<double>(steps), static_cast<double>(rejected)};
  if (failure.empty()) {
    report(wire::ResultKind::done, steps, t, 0, counts, sizeof counts);
    if (exchange.aborted()) failure = exchange.why();
  } else if (failure.rfind("stopped by the coordinator", 0) != 0 && failure.rfind("the coordinator", 0) != 0) {
    report(wire::ResultKind::failed, steps, t, 0, failure.data(), failure.size());
  }
  // The sockets stay open until the coordinator's word: the last results and boundary
  // values may still be on their way (linger 0).
  return {failure, control_.next_command(control_.timeouts().lost_s + 1.0)};
}

}  // namespace mbsflow
