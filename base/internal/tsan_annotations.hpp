#pragma once
// ThreadSanitizer cannot see the synchronisation inside oneTBB when libtbb is not built
// with it (Debian's is not): a flow-graph node's reads of what its predecessors wrote, or
// the main thread's reads after wait_for_all(), look like races. These annotations state
// the happens-before edges that TBB guarantees; they compile to nothing without TSan.
#if defined(__SANITIZE_THREAD__)
#include <sanitizer/tsan_interface.h>
#endif

namespace mbsflow {

inline void happens_before(const void* token) {
#if defined(__SANITIZE_THREAD__)
  __tsan_release(const_cast<void*>(token));
#else
  (void)token;
#endif
}

inline void happens_after(const void* token) {
#if defined(__SANITIZE_THREAD__)
  __tsan_acquire(const_cast<void*>(token));
#else
  (void)token;
#endif
}

// The same on the way out of a scope, exceptions included: a task's release of what it
// wrote, and the waiting thread's acquire of what the tasks wrote.
struct ReleaseOnExit {
  const void* token;
  ~ReleaseOnExit() { happens_before(token); }
};
struct AcquireOnExit {
  const void* token;
  ~AcquireOnExit() { happens_after(token); }
};

}  // namespace mbsflow
