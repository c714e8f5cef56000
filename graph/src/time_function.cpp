#include "mbsflow/graph/time_function.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mbsflow {
namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

// splitmix64: a fixed, portable hash so that a seed means the same function everywhere.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

double unit_double(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

FunctionValue sinusoid(double amplitude, double omega, double arg) {
  const double s = std::sin(arg), c = std::cos(arg);
  return {amplitude * s, amplitude * omega * c, -amplitude * omega * omega * s};
}

FunctionValue table_value(const TimeFunction& f, double t) {
  const auto& ts = f.times;
  const auto& vs = f.values;
  if (ts.empty()) return {};
  if (t <= ts.front()) return {vs.front(), 0.0, 0.0};
  if (t >= ts.back()) return {vs.back(), 0.0, 0.0};
  const auto i = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
  const double slope = (vs[i + 1] - vs[i]) / (ts[i + 1] - ts[i]);
  return {vs[i] + slope * (t - ts[i]), slope, 0.0};
}

FunctionValue random_value(const TimeFunction& f, double t) {
  FunctionValue sum;
  const int n = std::max(1, f.components);
  const double a = f.amplitude * std::sqrt(2.0 / n);
  for (int k = 0; k < n; ++k) {
    const std::uint64_t h = mix(f.seed * 0x100000001B3ull + static_cast<std::uint64_t>(k));
    const double jitter = unit_double(mix(h));
    const double omega = two_pi * f.cutoff * (k + jitter) / n;
    const FunctionValue s = sinusoid(a, omega, omega * t + two_pi * unit_double(h));
    sum.value += s.value;
    sum.rate += s.rate;
    sum.accel += s.accel;
  }
  return sum;
}

}  // namespace

TimeFunction TimeFunction::harmonic(double amplitude, double frequency_hz, double phase) {
  TimeFunction f;
  f.kind = Kind::harmonic;
  f.amplitude = amplitude;
  f.frequency = frequency_hz;
  f.phase = phase;
  return f;
}

TimeFunction TimeFunction::random(double rms, double cutoff_hz, std::uint64_t seed, int components) {
  TimeFunction f;
  f.kind = Kind::random;
  f.amplitude = rms;
  f.cutoff = cutoff_hz;
  f.seed = seed;
  f.components = components;
  return f;
}

FunctionValue evaluate(const TimeFunction& f, double t) {
  t -= f.delay;
  switch (f.kind) {
    case TimeFunction::Kind::constant:
      return {f.value, 0.0, 0.0};
    case TimeFunction::Kind::harmonic: {
      const double omega = two_pi * f.frequency;
      FunctionValue v = sinusoid(f.amplitude, omega, omega * t + f.phase);
      v.value += f.offset;
      return v;
    }
    case TimeFunction::Kind::table:
      return table_value(f, t);
    case TimeFunction::Kind::random:
      return random_value(f, t);
  }
  return {};
}

}  // namespace mbsflow
