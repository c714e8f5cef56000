// lane_kernels.cpp built for AVX: four lanes, each kernel's name with the suffix _avx
// (graph/CMakeLists.txt gives this file -mavx and Eigen's SSE alignment, so that the
// classes it shares with the other files keep their layout). MultibodySystem calls these
// kernels only where the CPU has AVX (simd.hpp).
#ifndef __AVX__
#error "lane_kernels_avx.cpp needs -mavx"
#endif
#define MBSFLOW_LANE_KERNEL_SUFFIX
#include "lane_kernels.cpp"
