#include "mbsflow/runtime/partitioned_run.hpp"

#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/flow_graph.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <chrono>
#include <memory>
#include <numeric>

#include "mbsflow/graph/error.hpp"
#include "partitioned_state.hpp"
#include "sink_runner.hpp"
#include "step_grid.hpp"

namespace mbsflow {
namespace {

using Clock = std::chrono::steady_clock;
using partitioned::Part;
namespace flow = tbb::flow;

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

// The work of submodel p at stage s of step n.
void stage_work(std::vector<Part>& parts, std::size_t p, int s, const StepGrid& grid, long n) {
  partitioned::pull_ghosts(parts, p, s);
  partitioned::stage(parts[p], s, grid.time(n), grid.time(n + 1));
}

// Steps of a chunk between snapshots: the graph is unrolled over these and built once.
// Node (c, p, s) is submodel p's stage s of the chunk's step c; it waits for stage s-1 of
// itself and of the neighbours it takes ghosts from (stage 3 of the previous step for s = 0).
class FlowGraphSchedule {
 public:
  FlowGraphSchedule(std::vector<Part>& parts, int chunk, BusyClock& clock) : start_(graph_) {
    const std::size_t k = parts.size();
    nodes_.reserve(static_cast<std::size_t>(chunk) * k * 4);
    for (int c = 0; c < chunk; ++c)
      for (std::size_t p = 0; p < k; ++p)
        for (int s = 0; s < 4; ++s)
          nodes_.push_back(std::make_unique<flow::continue_node<flow::continue_msg>>(
              graph_, [this, &parts, &clock, c, p, s](const flow::continue_msg&) {
                if (c < steps_) clock.time([&] { stage_work(parts, p, s, *grid_, first_ + c); });
                return flow::continue_msg();
              }));
    auto node = [&](int c, std::size_t p, int s) -> flow::continue_node<flow::continue_msg>& {
      return *nodes_[(static_cast<std::size_t>(c) * k + p) * 4 + static_cast<std::size_t>(s)];
    };
    // A finishing node runs the last of its successors that became ready itself and leaves
    // the others to be stolen. Registering each submodel's own next stage last keeps a
    // thread on its submodel (its data stays in that core's cache) while neighbours' next
    // stages go to their own threads.
    for (int c = 0; c < chunk; ++c) {
      for (std::size_t p = 0; p < k; ++p)
        for (const auto& e : parts[p].sub->exchanges) {
          const auto q = static_cast<std::size_t>(e.neighbour);
          for (int s = 1; s < 4; ++s) flow::make_edge(node(c, q, s - 1), node(c, p, s));
          if (c > 0) flow::make_edge(node(c - 1, q, 3), node(c, p, 0));
        }
      for (std::size_t p = 0; p < k; ++p) {
        for (int s = 1; s < 4; ++s) flow::make_edge(node(c, p, s - 1), node(c, p, s));
        if (c > 0) flow::make_edge(node(c - 1, p, 3), node(c, p, 0));
        if (c == 0) flow::make_edge(start_, node(0, p, 0));
      }
    }
  }

  void run(const StepGrid& grid, long first, int steps) {
    grid_ = &grid;
    first_ = first;
    steps_ = steps;
    start_.try_put(flow::continue_msg());
    graph_.wait_for_all();
  }

 private:
  flow::graph graph_;
  flow::broadcast_node<flow::continue_msg> start_;
  std::vector<std::unique_ptr<flow::continue_node<flow::continue_msg>>> nodes_;
  const StepGrid* grid_ = nullptr;
  long first_ = 0;
  int steps_ = 0;
};

// The seed's scheme: every stage, all submodels compute, then all exchange (a barrier).
void run_barrier(std::vector<Part>& parts, BusyClock& clock, const StepGrid& grid, long first, int steps) {
  for (int c = 0; c < steps; ++c)
    for (int s = 0; s < 4; ++s)
      tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t p) {
        clock.time([&] { stage_work(parts, p, s, grid, first + c); });
      }, tbb::simple_partitioner());
}

// Steps per chunk: snapshots fall on chunk ends; at most 64 steps unrolled.
int chunk_length(int output_every) {
  for (int c = std::min(output_every, 64); c > 1; --c)
    if (output_every % c == 0) return c;
  return 1;
}

}  // namespace

int default_partitions(const Model& model, int threads) {
  return std::max(1, std::min(threads, static_cast<int>(model.bodies.size() / 64)));
}

RunSummary run_partitioned(const Model& model, const Decomposition& d, const RunOptions& o, const ParallelOptions& par,
                           ResultSink* sink, ParallelStats* stats) {
  if (o.method != Method::rk4) throw InputError("partitioned runs integrate with RK4 so far (use --method rk4 or --partitions 1)");
  if (!(o.t_end > o.t_start)) throw InputError("t_end must be greater than t_start");
  if (!(o.step > 0.0) || !std::isfinite(o.step)) throw InputError("the step must be a positive finite number");
  const int threads = par.threads > 0 ? par.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  RunSummary out;
  BusyClock clock;
  std::vector<Part> parts;
  parts.reserve(d.submodels.size());
  for (const Submodel& s : d.submodels) parts.emplace_back(model, s);
  MultibodySystem whole(model);  // for the sink: layout, names, energies
  const StateLayout& layout = whole.layout();
  const StepGrid grid = step_grid(o.t_start, o.t_end, o.step);
  const int chunk = chunk_length(o.output_every);
  // Like run_simulation, which gets its system built: the clock starts with the run.
  const auto start = Clock::now();
  Eigen::VectorXd y = whole.initial_state();
  if (sink) sink->begin(whole);
  run_with_sink(sink, out, [&] {
    if (sink) emit(whole, sink, o.t_start, y, out);
    arena.execute([&] {
      std::unique_ptr<FlowGraphSchedule> graph;
      if (par.executor == Executor::flow_graph) graph = std::make_unique<FlowGraphSchedule>(parts, chunk, clock);
      for (long done = 0; done < grid.steps;) {
        const int steps = static_cast<int>(std::min<long>(chunk, grid.steps - done));
        if (graph)
          graph->run(grid, done, steps);
        else
          run_barrier(parts, clock, grid, done, steps);
        done += steps;
        const double t = grid.time(done);
        if (auto dv = partitioned::check(parts)) throw RunError(divergence_message(model, *dv, t, o.method, o.step));
        check_stop(o, t);
        if (sink && (done % o.output_every == 0 || done == grid.steps)) {
          partitioned::gather(parts, layout, y);
          emit(whole, sink, t, y, out);
        }
        if (o.progress) o.progress(t, done);
      }
    });
  });
  partitioned::gather(parts, layout, y);
  out.steps = grid.steps;
  out.evaluations = grid.steps * 4;
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
