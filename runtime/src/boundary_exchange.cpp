#include "boundary_exchange.hpp"

#include "mbsflow/methods/dopri5.hpp"

namespace mbsflow {

void BoundaryExchange::fail(std::exception_ptr e) {
  std::lock_guard lock(failure_mutex_);
  if (failure_) return;
  failure_ = std::move(e);
  failed_.store(true, std::memory_order_release);
}

void BoundaryExchange::check() const {
  std::exception_ptr e;
  {
    std::lock_guard lock(failure_mutex_);
    e = failure_;
  }
  if (e) std::rethrow_exception(e);
}

double LocalExchange::error_sum(long, Eigen::VectorXd& squares) { return dopri5::ordered_sum(squares); }

}  // namespace mbsflow
