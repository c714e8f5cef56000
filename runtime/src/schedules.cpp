#include "schedules.hpp"

#include "tsan_annotations.hpp"

namespace mbsflow {

namespace flow = tbb::flow;

namespace {
// Orders a node's reading of its own captures after the thread that built and started the
// graph (for ThreadSanitizer; see tsan_annotations.hpp). Taken first, before any capture.
long start_token = 0;
}  // namespace

FlowGraphSchedule::FlowGraphSchedule(const std::vector<Submodel>& subs, int chunk, int stages, StageWork work,
                                     bool barriers, const RemoteInputs* remote, int lag)
    : start_(graph_), work_(std::move(work)) {
  const std::size_t k = subs.size();
  const auto n_stages = static_cast<std::size_t>(stages);
  const std::size_t halves = remote ? 2 : 1;
  auto is_local = [&](std::size_t p) { return !remote || remote->local[p]; };
  nodes_.reserve(static_cast<std::size_t>(chunk) * k * n_stages * halves);
  for (int c = 0; c < chunk; ++c)
    for (std::size_t p = 0; p < k; ++p)
      for (int s = 0; s < stages; ++s)
        for (std::size_t h = 0; h < halves; ++h) {
          const Half half = !remote ? Half::whole : h == 0 ? Half::inner : Half::edge;
          nodes_.push_back(!is_local(p) ? nullptr : std::make_unique<Node>(graph_, [this, c, p, s, half](const flow::continue_msg&) {
            happens_after(&start_token);
            if (c < steps_) work_(p, s, c, half);
            happens_before(&finish_token_);
            return flow::continue_msg();
          }));
        }
  auto node = [&](int c, std::size_t p, int s, std::size_t h) -> Node& {
    return *nodes_[((static_cast<std::size_t>(c) * k + p) * n_stages + static_cast<std::size_t>(s)) * halves + h];
  };
  auto first = [&](int c, std::size_t p, int s) -> Node& { return node(c, p, s, 0); };
  auto last = [&](int c, std::size_t p, int s) -> Node& { return node(c, p, s, halves - 1); };
  // Proxy for remote q's values of stage input s of step c, for local p.
  auto proxy = [&](int c, std::size_t q, std::size_t p, int s) -> Node& {
    proxies_.push_back(std::make_unique<Node>(graph_, [this, remote, c, q, p, s](const flow::continue_msg&) {
      happens_after(&start_token);
      if (c < steps_) remote->wait(c, q, p, s);
      happens_before(&finish_token_);
      return flow::continue_msg();
    }));
    return *proxies_.back();
  };
  // What local p's stage s follows: its previous stage, or the start.
  auto previous = [&](int c, std::size_t p, int s) -> flow::sender<flow::continue_msg>& {
    if (s > 0) return last(c, p, s - 1);
    if (c > 0) return last(c - 1, p, stages - 1);
    return start_;
  };
  // A finishing node runs the last of its successors that became ready itself and leaves
  // the others to be stolen. Registering each submodel's own next stage last keeps a
  // thread on its submodel (its data stays in that core's cache) while neighbours' next
  // stages go to their own threads.
  auto inputs = [&](std::size_t p) {  // the other submodels whose values p needs
    std::vector<std::size_t> q;
    if (barriers) {
      for (std::size_t o = 0; o < k; ++o)
        if (o != p) q.push_back(o);
    } else {
      for (const auto& e : subs[p].exchanges) q.push_back(static_cast<std::size_t>(e.neighbour));
    }
    return q;
  };
  for (int c = 0; c < chunk; ++c) {
    for (std::size_t p = 0; p < k; ++p) {
      if (!is_local(p)) continue;
      for (std::size_t q : inputs(p)) {
        if (!is_local(q)) continue;
        for (int s = 1; s < stages; ++s) flow::make_edge(last(c, q, s - 1), last(c, p, s));
        if (c > lag) flow::make_edge(last(c - 1 - lag, q, stages - 1), last(c, p, 0));
      }
    }
    for (std::size_t p = 0; p < k; ++p) {
      if (!is_local(p)) continue;
      for (int s = 0; s < stages; ++s) {
        // previous stage -> [inner half] -> proxy -> ... -> proxy -> this stage (or its edge half)
        flow::sender<flow::continue_msg>* before = &previous(c, p, s);
        if (halves == 2) {
          flow::make_edge(*before, first(c, p, s));
          before = &first(c, p, s);
        }
        for (std::size_t q : inputs(p)) {
          if (is_local(q)) continue;
          Node& x = proxy(c, q, p, s);
          flow::make_edge(*before, x);
          before = &x;
        }
        flow::make_edge(*before, last(c, p, s));
      }
    }
  }
}

void FlowGraphSchedule::run(int steps) {
  steps_ = steps;
  happens_before(&start_token);
  start_.try_put(flow::continue_msg());
  graph_.wait_for_all();
  happens_after(&finish_token_);  // every node's read of steps_ (also those past it) before the next run
}

Scheduler::Scheduler(const Decomposition& d, int chunk, int stages, StageWork work, bool barriers,
                     const RemoteInputs* remote, int lag)
    : subs_(d.submodels), tokens_(d.submodels.size()), work_([this, work](std::size_t p, int s, int c, Half half) {
        happens_after(&caller_);
        happens_after(&tokens_[p]);
        for (const auto& e : subs_[p].exchanges) happens_after(&tokens_[static_cast<std::size_t>(e.neighbour)]);
        work(p, s, c, half);
        happens_before(&tokens_[p]);
      }) {
  graph_ = std::make_unique<FlowGraphSchedule>(d.submodels, chunk, stages, work_, barriers, remote, lag);
}

void Scheduler::run(int steps) {
  happens_before(&caller_);
  graph_->run(steps);
  for (const long& t : tokens_) happens_after(&t);
}

}  // namespace mbsflow
