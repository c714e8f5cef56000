// A worker's part of a tightly coupled run: the loop of tight_coupling.hpp over its local
// submodels, with the boundary values of the others through the WorkerExchange and the
// results to the coordinator (docs/cluster.md).
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <memory>
#include <stdexcept>
#include <optional>

#include "mbsflow/error.hpp"
#include "tight_coupling.hpp"
#include "worker_part.hpp"

namespace mbsflow {
namespace {

using partitioned::Part;

// Results to the coordinator; a stop (aborted, diverged, interrupted) is thrown.
class TightCoordinatorOutput final : public RunObserver {
 public:
  explicit TightCoordinatorOutput(WorkerPart& w) : w_(w) {}
  void step_done(long steps, double t, long snapshot) override {
    steps_ = steps;
    t_ = t;
    if (std::string failure = w_.check(t); !failure.empty()) throw RunError(failure);
    w_.report_state(steps, t, snapshot);
  }
  void dense(long index, double t, Eigen::VectorXd& y, bool projected) override {
    w_.report_dense(steps_, t, index, y, !projected);
  }
  bool checkpoint_due() override { return w_.checkpoint_due(); }
  // The point and the own bodies (the coordinator puts the global state together).
  void checkpoint(const std::function<void(StateWriter&)>& save) override {
    std::vector<double> own;
    w_.pack_own(own);
    StateWriter out;
    save(out);
    out.vector(Eigen::Map<const Eigen::VectorXd>(own.data(), static_cast<Eigen::Index>(own.size())));
    w_.send_checkpoint(out.take());
  }
  long steps() const { return steps_; }
  double t() const { return t_; }

 private:
  WorkerPart& w_;
  long steps_ = 0;
  double t_ = 0.0;
};

}  // namespace

void prepare_tight(Session& s) {
  const int stages = tight_stages(s.o.method);
  const std::size_t k = s.d.submodels.size();
  s.tight_parts.clear();
  s.tight_parts.resize(k);
  for (std::size_t q = 0; q < k; ++q)
    if (s.worker_of[q] == s.me) s.tight_parts[q] = std::make_unique<Part>(s.model, s.d.submodels[q], stages, true);
}

Outcome run_tight(Session& s, WorkerTransport& transport, const nlohmann::json& start, int threads,
                  const std::atomic<bool>* stop) {
  const int stages = tight_stages(s.o.method);
  // serve_worker made them (prepare_tight) before it said ready: not in the timed run.
  if (s.tight_parts.size() != s.d.submodels.size()) throw std::logic_error("run_tight: the local submodels were not prepared");
  std::vector<Part*> parts;
  for (const auto& p : s.tight_parts) parts.push_back(p.get());
  WorkerPart w(s, transport, start, parts, stages, stop);
  TightCoordinatorOutput output(w);
  std::string failure;
  TightCounts counts;
  std::optional<TightPoint> resumed;
  if (!s.resume.empty()) {  // the coordinator's checkpoint: the point and the global state
    StateReader in(s.resume, "the coordinator's checkpoint");
    const StateLayout global = s.d.layout();
    Eigen::VectorXd y;
    resumed = read_tight_point(in, global.size(), y);
    for (Part* p : parts)
      if (p) partitioned::scatter(y, global, *p);
  }
  // A proxy waits on its thread (see RemoteInputs): one thread per local submodel at least.
  tbb::task_arena arena(std::max(threads > 0 ? threads : tbb::info::default_concurrency(), static_cast<int>(w.mine.size())));
  try {
    arena.execute([&] { counts = run_tight_coupling({s.d, parts, s.o, w.exchange, output, false, nullptr, resumed ? &*resumed : nullptr}); });
  } catch (const std::exception& e) {
    failure = error_text(e);
  }
  return w.finish(failure, failure.empty() ? counts.steps : output.steps(), failure.empty() ? s.o.t_end : output.t(),
                  static_cast<double>(counts.evaluations), counts.rejected);
}

}  // namespace mbsflow
