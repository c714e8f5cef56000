#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/graph/time_function.hpp"

using namespace mbsflow;

namespace {
// Central differences of value and rate, to check the analytic derivatives.
void check_derivatives(const TimeFunction& f, double t) {
  const double h = 1e-5;
  const FunctionValue a = evaluate(f, t - h), b = evaluate(f, t + h), v = evaluate(f, t);
  CHECK(v.rate == Approx((b.value - a.value) / (2 * h)).margin(1e-6));
  CHECK(v.accel == Approx((b.rate - a.rate) / (2 * h)).margin(1e-4));
}
}  // namespace

TEST_CASE("harmonic function: value and analytic derivatives", "[graph]") {
  TimeFunction f = TimeFunction::harmonic(2.0, 1.5, 0.3);
  f.offset = 0.5;
  const double w = 2 * M_PI * 1.5;
  CHECK(evaluate(f, 0.2).value == Approx(0.5 + 2.0 * std::sin(w * 0.2 + 0.3)).epsilon(1e-14));
  check_derivatives(f, 0.2);
  f.delay = 0.1;
  CHECK(evaluate(f, 0.3).value == Approx(0.5 + 2.0 * std::sin(w * 0.2 + 0.3)).epsilon(1e-14));
}

TEST_CASE("table function interpolates linearly and holds its end values", "[graph]") {
  TimeFunction f;
  f.kind = TimeFunction::Kind::table;
  f.times = {0.0, 1.0, 3.0};
  f.values = {0.0, 2.0, 1.0};
  CHECK(evaluate(f, -1.0).value == 0.0);
  CHECK(evaluate(f, 0.5).value == Approx(1.0));
  CHECK(evaluate(f, 0.5).rate == Approx(2.0));
  CHECK(evaluate(f, 2.0).value == Approx(1.5));
  CHECK(evaluate(f, 5.0).value == 1.0);
  CHECK(evaluate(f, 5.0).rate == 0.0);
}

TEST_CASE("random function: deterministic, band-limited, with the requested rms", "[graph]") {
  const TimeFunction f = TimeFunction::random(0.3, 10.0, 42, 64);
  CHECK(evaluate(f, 1.234).value == evaluate(f, 1.234).value);
  const TimeFunction g = TimeFunction::random(0.3, 10.0, 43, 64);
  CHECK(evaluate(f, 1.234).value != evaluate(g, 1.234).value);
  // Mean square over a long window approaches amplitude^2.
  double sum = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) sum += std::pow(evaluate(f, i * 1e-3).value, 2);
  CHECK(std::sqrt(sum / n) == Approx(0.3).epsilon(0.05));
  // No content above the cutoff: |rate| <= 2 pi fc sqrt(2 n) a/sqrt(n) bound of the sum.
  check_derivatives(f, 0.77);
}
