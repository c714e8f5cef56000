#include "mbsflow/graph/simd.hpp"

#include <atomic>
#include <cstdlib>
#include <cstring>

namespace mbsflow {
namespace {

bool cpu_has_avx() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();  // in case this runs before libgcc's own constructor
  return __builtin_cpu_supports("avx");  // checks that the OS saves the AVX registers too
#else
  return false;
#endif
}

Simd initial() {
  const char* forced = std::getenv("MBSFLOW_SIMD");
  if (forced && std::strcmp(forced, "sse2") == 0) return Simd::sse2;
  return cpu_has_avx() ? Simd::avx : Simd::sse2;
}

std::atomic<Simd>& current() {
  static std::atomic<Simd> s{initial()};
  return s;
}

}  // namespace

Simd simd() { return current().load(std::memory_order_relaxed); }

bool set_simd(Simd s) {
  if (s == Simd::avx && !cpu_has_avx()) return false;
  current().store(s, std::memory_order_relaxed);
  return true;
}

}  // namespace mbsflow
