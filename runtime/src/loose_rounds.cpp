#include "loose_rounds.hpp"

#include <oneapi/tbb/info.h>

#include <algorithm>

#include "mbsflow/runtime/divergence.hpp"

namespace mbsflow::loose {

std::unique_ptr<LoosePart> make_part(const Model& model, const Submodel& sub, const RunOptions& o, const LooseOptions& lo,
                                     std::size_t q) {
  const Method method = lo.methods.empty() ? o.method : lo.methods[q];
  return std::make_unique<LoosePart>(model, sub, o, method, lo.extrapolation, 2 * lo.max_lag + 3);
}

namespace {
// A proxy waits on its thread (schedules.hpp): at least one thread per local submodel.
int arena_threads(const LooseOptions& lo, const std::vector<std::unique_ptr<LoosePart>>& parts, bool remote) {
  const int wanted = lo.threads > 0 ? lo.threads : tbb::info::default_concurrency();
  if (!remote) return wanted;
  const auto local = std::count_if(parts.begin(), parts.end(), [](const auto& p) { return p != nullptr; });
  return std::max(wanted, static_cast<int>(local));
}
}  // namespace

LooseRounds::LooseRounds(const Model& model, const Decomposition& d, const RunOptions& o, const LooseOptions& lo,
                         std::vector<std::unique_ptr<LoosePart>>& parts, const MacroGrid& grid, int chunk,
                         RemoteSamples* remote)
    : model_(model), o_(o), lag_(lo.max_lag), reach_(overlap_reach(lo)), exact_(lo.exact_lag), parts_(parts), grid_(grid), remote_(remote),
      logs_(parts.size()), scratch_(parts.size()), arena_(arena_threads(lo, parts, remote != nullptr)) {
  if (remote_) {
    inputs_.local.resize(parts.size());
    for (std::size_t q = 0; q < parts.size(); ++q) inputs_.local[q] = parts[q] ? 1 : 0;
    inputs_.wait = [this](int c, std::size_t q, std::size_t p, int) {
      remote_->wait(first_ + c - lag_, static_cast<int>(q), static_cast<int>(p));
    };
  }
  arena_.execute([&] {
    schedule_ = std::make_unique<Scheduler>(
        d, chunk, 1,
        [this](std::size_t p, int, int c, Half half) {
          if (half != Half::inner) step(p, first_ + c);  // a macro step has no part free of ghosts
        },
        false, remote_ ? &inputs_ : nullptr, lag_);
  });
}

LooseRounds::~LooseRounds() {
  arena_.execute([&] { schedule_.reset(); });
}

std::string LooseRounds::run(long first, int n) {
  first_ = first;
  arena_.execute([&] { schedule_->run(n); });
  std::lock_guard lock(failure_mutex_);
  return failure_;
}

void LooseRounds::fail(const std::string& why) {
  {
    std::lock_guard lock(failure_mutex_);
    if (failure_.empty()) failure_ = why;
  }
  failed_ = true;
  if (remote_) remote_->abort(why);
}

bool LooseRounds::stopped() const { return failed_ || (remote_ && remote_->stopped()); }

void LooseRounds::pull(std::size_t p, long cap) {
  LoosePart& lp = *parts_[p];
  const std::vector<Submodel::Exchange>& exchanges = lp.part.sub->exchanges;
  for (std::size_t e = 0; e < exchanges.size(); ++e) {
    const Submodel::Exchange& x = exchanges[e];
    auto take = [&](long index, const double* packed) {
      if (index <= lp.taken(e)) return;
      if (const std::optional<CouplingError> err = lp.take(e, index, grid_.end(index), packed))
        logs_[p].push_back({index, grid_.end(index - 1), grid_.end(index), err->position, err->velocity, 0});
    };
    if (const LoosePart* owner = parts_[static_cast<std::size_t>(x.neighbour)].get()) {
      const long upto = std::min(cap, owner->published());
      std::vector<double>& buffer = scratch_[p];
      buffer.resize(x.from.size() * partitioned::body_numbers);
      for (long i = lp.taken(e) + 1; i <= upto; ++i) {
        owner->pack_published(i, x.from, buffer.data());
        take(i, buffer.data());
      }
    } else {
      remote_->take(static_cast<int>(p), x.neighbour, cap, take);
    }
  }
}

void LooseRounds::step(std::size_t p, long m) {
  if (stopped()) return;
  LoosePart& lp = *parts_[p];
  try {
    pull(p, exact_ ? m - lag_ : m);
    long newest = m;
    for (std::size_t e = 0; e < lp.part.sub->exchanges.size(); ++e) newest = std::min(newest, lp.taken(e));
    const double t0 = grid_.end(m), t1 = grid_.end(m + 1);
    logs_[p].push_back({m + 1, t0, t1, 0.0, 0.0, static_cast<int>(m - std::max(newest, 0L))});
    lp.reset_borrowed(m);
    lp.integrate(t0, t1, keep_snapshots ? grid_.outputs_in(t0, t1) : std::vector<std::pair<long, double>>{});
    lp.predict(m + 1, t1);
    if (auto dv = partitioned::check(lp.part))
      return fail(loose_divergence_message(model_, *dv, t1, o_.method, o_.step, t1 - t0, lag_, reach_));
    lp.publish(m + 1, t1);
    if (remote_) remote_->send(static_cast<int>(p), m + 1);
  } catch (const std::exception& e) {
    fail(error_text(e));
  }
}

void LooseRounds::catch_up(long index) {
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    if (!parts_[p]) continue;
    if (remote_)
      for (const Submodel::Exchange& x : parts_[p]->part.sub->exchanges)
        if (!parts_[static_cast<std::size_t>(x.neighbour)]) remote_->wait(index, x.neighbour, static_cast<int>(p));
    if (stopped()) return;
    pull(p, index);
  }
}

CouplingError LooseRounds::worst(long index) const {
  CouplingError most;
  for (const auto& records : logs_)
    for (const CouplingRecord& r : records)
      if (r.index == index) {
        most.position = std::max(most.position, r.position_error);
        most.velocity = std::max(most.velocity, r.velocity_error);
      }
  return most;
}

void LooseRounds::drain(CouplingLog& log) {
  for (auto& records : logs_) {
    for (const CouplingRecord& r : records) log.add(r);
    records.clear();
  }
}

void LooseRounds::discard(long index) {
  for (auto& records : logs_)
    records.erase(std::remove_if(records.begin(), records.end(), [index](const CouplingRecord& r) { return r.index >= index; }),
                  records.end());
}

}  // namespace mbsflow::loose
