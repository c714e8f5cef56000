#pragma once
// Boundary data between the submodels of a tightly coupled run, keyed by (step, stage):
// the ghost values a stage needs before it runs, the values it makes for the neighbours,
// and the one global reduction a step attempt needs (DOPRI5's error norm). The run loop
// (tight_coupling.hpp) never asks where a neighbour runs: LocalExchange copies from the
// submodels of this process; RemoteExchange (remote_exchange.hpp) does that too and talks
// ZeroMQ to the other workers. The values are the same bits either way, and the error
// norm adds the same terms in the same (global element) order, so a run's results do not
// depend on where its submodels run.
#include <Eigen/Core>
#include <atomic>
#include <exception>
#include <mutex>
#include <vector>

#include "partitioned_state.hpp"

namespace mbsflow {

class BoundaryExchange {
 public:
  virtual ~BoundaryExchange() = default;

  // The ghost values of stage input s of step n into local submodel p, once they are in.
  virtual void take(std::size_t p, long n, int s) = 0;
  // Local submodel p's values of stage input s of step n, for the neighbours that need them.
  // Every value a take reads was offered first, the state a run starts from included
  // (run_tight_coupling offers it): an exchange may copy the values when offered.
  virtual void offer(std::size_t p, long n, int s) = 0;
  // The sum over every submodel's own entries of `squares`, in global element order, for
  // attempt n. On entry the local submodels' entries are set; on return all are.
  virtual double error_sum(long n, Eigen::VectorXd& squares) = 0;

  // Per submodel, 1 if its stages run here; null when they all do. The schedule then puts
  // a proxy node per remote neighbour before a stage, whose body calls wait.
  virtual const std::vector<char>* local_submodels() const { return nullptr; }
  // Returns once remote q's values of stage input s of step n for local p are in (or the
  // exchange stopped).
  virtual void wait(long /*n*/, int /*s*/, int /*q*/, int /*p*/) {}

  // A stage failed: the first failure is kept and the stages still to come do nothing.
  virtual void fail(std::exception_ptr e);
  virtual bool stopped() const { return failed_.load(std::memory_order_acquire); }
  // Rethrows the first failure, if any (after a schedule's run).
  virtual void check() const;

 private:
  mutable std::mutex failure_mutex_;
  std::exception_ptr failure_;
  std::atomic<bool> failed_{false};
};

// All submodels in this process: ghosts are copied from their owners' stage inputs.
class LocalExchange final : public BoundaryExchange {
 public:
  explicit LocalExchange(std::vector<partitioned::Part*> parts) : parts_(std::move(parts)) {}
  void take(std::size_t p, long, int s) override { partitioned::copy_local_ghosts(parts_, p, s); }
  void offer(std::size_t, long, int) override {}
  double error_sum(long n, Eigen::VectorXd& squares) override;

 private:
  std::vector<partitioned::Part*> parts_;
};

}  // namespace mbsflow
