#pragma once
// Doubles computed side by side (a GCC vector: two in an SSE2 register, the baseline build;
// four in an AVX one, in the file compiled for AVX), usable as an Eigen scalar. The
// force-law and rotation templates (force_laws.hpp, rotation.hpp) run on it unchanged to
// evaluate several bushings or bodies at once (lane_kernels.cpp). Each width lives in a
// namespace of its own, so that no template instantiated on it is shared between files
// built for different instruction sets.
//
// Every operation acts on each lane alone, with an IEEE operation (no fused multiply-add:
// neither build enables FMA), so what a lane computes does not depend on what the other
// lanes hold, nor on the width. That keeps a run bitwise identical whichever items a
// partition happens to evaluate together, on SSE2 or AVX. Against the same templates in
// double a lane agrees to rounding only: Eigen sums a custom scalar's dot products and
// matrix products in another order than its double packets do.
#include <Eigen/Core>
#include <cmath>
#include <emmintrin.h>
#include <type_traits>

#if !defined(__SSE2__)
#error "lanes.hpp needs x86-64 (SSE2)"
#endif
#ifdef __AVX__
#include <immintrin.h>
#define MBSFLOW_LANES_NAMESPACE lanes_avx
#define MBSFLOW_LANE_BYTES 32
#else
#define MBSFLOW_LANES_NAMESPACE lanes_sse2
#define MBSFLOW_LANE_BYTES 16
#endif

namespace mbsflow {
inline namespace MBSFLOW_LANES_NAMESPACE {

struct LaneMask {
  using Vec = long long __attribute__((vector_size(MBSFLOW_LANE_BYTES)));
  Vec m;
};

struct Lanes {
  using Vec = double __attribute__((vector_size(MBSFLOW_LANE_BYTES)));
  static constexpr int width = MBSFLOW_LANE_BYTES / 8;
  Vec v;

  Lanes() = default;  // uninitialised, as a double is
#ifdef __AVX__
  Lanes(double x) : v(Vec(_mm256_set1_pd(x))) {}
#else
  Lanes(double x) : v(Vec(_mm_set1_pd(x))) {}
#endif
  Lanes(Vec x) : v(x) {}

  Lanes& operator+=(Lanes o) { v += o.v; return *this; }
  Lanes& operator-=(Lanes o) { v -= o.v; return *this; }
  Lanes& operator*=(Lanes o) { v *= o.v; return *this; }
  Lanes& operator/=(Lanes o) { v /= o.v; return *this; }
  friend Lanes operator+(Lanes a, Lanes b) { return a.v + b.v; }
  friend Lanes operator-(Lanes a, Lanes b) { return a.v - b.v; }
  friend Lanes operator*(Lanes a, Lanes b) { return a.v * b.v; }
  friend Lanes operator/(Lanes a, Lanes b) { return a.v / b.v; }
  friend Lanes operator-(Lanes a) { return -a.v; }
  friend Lanes operator+(Lanes a) { return a; }
  friend LaneMask operator<(Lanes a, Lanes b) { return {a.v < b.v}; }
  friend LaneMask operator<=(Lanes a, Lanes b) { return {a.v <= b.v}; }
  friend LaneMask operator>(Lanes a, Lanes b) { return {a.v > b.v}; }
  friend LaneMask operator>=(Lanes a, Lanes b) { return {a.v >= b.v}; }
};

inline bool all_lanes(LaneMask a) {
  for (int l = 0; l < Lanes::width; ++l)
    if (!a.m[l]) return false;
  return true;
}
inline bool no_lane(LaneMask a) {
  for (int l = 0; l < Lanes::width; ++l)
    if (a.m[l]) return false;
  return true;
}

// Lane by lane: a where the mask is set, else b.
inline Lanes select(LaneMask m, Lanes a, Lanes b) { return m.m ? a.v : b.v; }

// Correctly rounded, as std::sqrt.
#ifdef __AVX__
inline Lanes sqrt(Lanes a) { return Lanes(Lanes::Vec(_mm256_sqrt_pd(__m256d(a.v)))); }
#else
inline Lanes sqrt(Lanes a) { return Lanes(Lanes::Vec(_mm_sqrt_pd(__m128d(a.v)))); }
#endif

inline Lanes atan2(Lanes y, Lanes x) {
  Lanes r;
  for (int i = 0; i < Lanes::width; ++i) r.v[i] = std::atan2(y.v[i], x.v[i]);
  return r;
}

template <class S>
inline constexpr bool is_lanes_v = std::is_same_v<S, Lanes>;

// The scalar a constant takes beside S: Lanes for Lanes, double for double and dual numbers.
template <class S>
using LaneConstant = std::conditional_t<is_lanes_v<S>, Lanes, double>;

// The branch of a comparison, for code templated on the scalar: for a double or a dual
// number only the taken branch is evaluated; for Lanes both are (unless every lane takes
// the same one) and each lane keeps its own.
template <class F, class G>
auto pick(bool c, F&& taken, G&& other) {
  return c ? taken() : other();
}
template <class F, class G>
Lanes pick(LaneMask c, F&& taken, G&& other) {
  if (all_lanes(c)) return taken();
  if (no_lane(c)) return other();
  return select(c, taken(), other());
}

// Walks items list[0..n) (0..n-1 when list is null) in order: classify(k) gives an item's
// class in [0, Classes), or -1 for single(k) at once; the items of a class go to
// group(const int*) Width at a time, and a class's last incomplete group repeats its last
// item.
template <int Classes, int Width = Lanes::width, class Classify, class Single, class Group>
void in_lane_groups(const int* list, std::size_t n, Classify&& classify, Single&& single, Group&& group) {
  int pending[Classes][Width];
  int count[Classes] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const int k = list ? list[i] : static_cast<int>(i);
    const int c = classify(k);
    if (c < 0) {
      single(k);
      continue;
    }
    pending[c][count[c]++] = k;
    if (count[c] == Width) {
      group(pending[c]);
      count[c] = 0;
    }
  }
  for (int c = 0; c < Classes; ++c) {
    if (count[c] == 0) continue;
    for (int l = count[c]; l < Width; ++l) pending[c][l] = pending[c][count[c] - 1];
    group(pending[c]);
  }
}

// The matrix whose coefficient (r, c) holds, in lane l, coefficient (r, c) of of(l).
template <class Of>
auto gather(Of&& of) {
  using M = typename std::decay_t<decltype(of(0))>::PlainObject;
  Eigen::Matrix<Lanes, M::RowsAtCompileTime, M::ColsAtCompileTime> out;
  for (Eigen::Index c = 0; c < out.cols(); ++c)
    for (Eigen::Index r = 0; r < out.rows(); ++r) {
      Lanes x;
      for (int l = 0; l < Lanes::width; ++l) x.v[l] = of(l)(r, c);
      out(r, c) = x;
    }
  return out;
}

// The matrix whose coefficients hold m's in every lane (what gather gives when of(l) is
// the same matrix for every l, in fewer instructions).
template <class M>
auto broadcast(const M& m) {
  using P = typename M::PlainObject;
  Eigen::Matrix<Lanes, P::RowsAtCompileTime, P::ColsAtCompileTime> out;
  for (Eigen::Index c = 0; c < out.cols(); ++c)
    for (Eigen::Index r = 0; r < out.rows(); ++r) out(r, c) = Lanes(m(r, c));
  return out;
}

// Field `field` of the items item[0..width) on lanes: broadcast when every lane holds the
// same item (one_item: repeated laws of a chain or grid), else gathered lane by lane.
template <class Item>
[[gnu::always_inline]] inline bool one_item(const Item* const* item) {
  for (int l = 1; l < Lanes::width; ++l)
    if (item[l] != item[0]) return false;
  return true;
}
template <class Item, class M>
[[gnu::always_inline]] inline auto lanes_of(const Item* const* item, bool one, M Item::*field) {
  return one ? broadcast(item[0]->*field) : gather([&](int l) -> auto& { return item[l]->*field; });
}

// The other way: lane l of m into to(l), an Eigen block of m's size.
template <class M, class To>
void scatter(const M& m, To&& to) {
  for (int l = 0; l < Lanes::width; ++l) {
    auto&& dst = to(l);
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      for (Eigen::Index r = 0; r < m.rows(); ++r) dst(r, c) = m(r, c).v[l];
  }
}

}  // namespace MBSFLOW_LANES_NAMESPACE
}  // namespace mbsflow

namespace Eigen {
template <>
struct NumTraits<mbsflow::Lanes> : NumTraits<double> {
  using Real = mbsflow::Lanes;
  using NonInteger = mbsflow::Lanes;
  using Nested = mbsflow::Lanes;
  using Literal = mbsflow::Lanes;
};
template <class Op>
struct ScalarBinaryOpTraits<mbsflow::Lanes, double, Op> {
  using ReturnType = mbsflow::Lanes;
};
template <class Op>
struct ScalarBinaryOpTraits<double, mbsflow::Lanes, Op> {
  using ReturnType = mbsflow::Lanes;
};
}  // namespace Eigen
