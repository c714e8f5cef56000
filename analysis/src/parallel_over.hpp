#pragma once
// The analysis's loops over bodies and joints on all cores (oneTBB).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "mbsflow/graph/multibody_system.hpp"
#include "tsan_annotations.hpp"

namespace mbsflow {

// body(begin, end) over [0, count) on all cores, with the orderings tbb::parallel_for
// guarantees stated to ThreadSanitizer (Debian's libtbb is not instrumented): the tasks see
// what the caller wrote before, the caller what the tasks wrote.
template <class F>
void parallel_over(std::size_t count, F body) {
  int token = 0;
  happens_before(&token);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& range) {
    happens_after(&token);
    const ReleaseOnExit release{&token};
    body(range.begin(), range.end());
  });
  happens_after(&token);
}

// parallel_over as MultibodySystem::jacobian takes it.
inline MultibodySystem::ParallelFor all_cores() {
  return [](std::size_t count, const std::function<void(std::size_t, std::size_t)>& body) { parallel_over(count, body); };
}

}  // namespace mbsflow
