#pragma once
// Scalar functions of time with first and second derivatives, for loads and drivers.
#include <cstdint>
#include <vector>

namespace mbsflow {

struct TimeFunction {
  enum class Kind { constant, harmonic, table, random };
  Kind kind = Kind::constant;
  double value = 1.0;      // constant
  double amplitude = 0.0;  // harmonic: amplitude; random: root-mean-square value
  double frequency = 0.0;  // harmonic, in Hz
  double phase = 0.0;      // harmonic, in radians
  double offset = 0.0;     // harmonic
  std::vector<double> times, values;  // table: piecewise linear, held constant outside
  std::uint64_t seed = 0;  // random
  double cutoff = 0.0;     // random: highest frequency in Hz
  int components = 32;     // random: number of sinusoids, 1 to max_components
  static constexpr int max_components = 65536;
  double delay = 0.0;      // every kind: evaluated at t - delay

  static TimeFunction constant(double v) { TimeFunction f; f.value = v; return f; }
  static TimeFunction harmonic(double amplitude, double frequency_hz, double phase = 0.0);
  static TimeFunction random(double rms, double cutoff_hz, std::uint64_t seed, int components = 32);
};

struct FunctionValue {
  double value = 0.0;
  double rate = 0.0;   // d/dt
  double accel = 0.0;  // d2/dt2
};

// Band-limited random functions are sums of `components` sinusoids with frequencies
// spread over (0, cutoff] and phases drawn from the seed: deterministic on every
// platform, smooth, with the given root-mean-square value.
FunctionValue evaluate(const TimeFunction& f, double t);

}  // namespace mbsflow
