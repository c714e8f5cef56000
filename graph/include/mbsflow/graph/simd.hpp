#pragma once
// The instruction set the right-hand side's bushings run on (graph/src/lanes.hpp): AVX,
// four at a time, where the CPU has it, else SSE2, two at a time. Both give the same
// numbers bit for bit (no fused multiply-add in either), so hosts of either kind can share
// a run. MBSFLOW_SIMD=sse2 in the environment keeps SSE2.
namespace mbsflow {

enum class Simd { sse2, avx };

Simd simd();
// For tests and benchmarks: false (and no change) where the CPU lacks it.
bool set_simd(Simd s);

}  // namespace mbsflow
