#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>

#include "mbsflow/methods/rk4.hpp"
#include "mbsflow/line_fit.hpp"

using namespace mbsflow;

namespace {
// y' = y cos t, y(0) = 1: y = exp(sin t).
auto problem() {
  return make_system(1, [](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) { dy[0] = y[0] * std::cos(t); });
}
}  // namespace

TEST_CASE("RK4 converges with order 4", "[methods]") {
  auto sys = problem();
  std::vector<double> hs, errs;
  for (int n : {20, 40, 80, 160, 320}) {
    Rk4 rk(1);
    Eigen::VectorXd y = Eigen::VectorXd::Constant(1, 1.0);
    const double h = 2.0 / n;
    for (int k = 0; k < n; ++k) rk.step(sys, k * h, h, y);
    hs.push_back(h);
    errs.push_back(std::abs(y[0] - std::exp(std::sin(2.0))));
  }
  const double slope = log_log_slope(hs, errs);
  INFO("slope " << slope);
  CHECK(slope > 3.8);
  CHECK(slope < 4.2);
}

TEST_CASE("RK4 is exact for cubic solutions", "[methods]") {
  auto sys = make_system(1, [](double t, const Eigen::VectorXd&, Eigen::VectorXd& dy) { dy[0] = 3 * t * t - 2 * t; });
  Rk4 rk(1);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(1);
  for (int k = 0; k < 7; ++k) rk.step(sys, 0.3 * k, 0.3, y);
  const double t = 2.1;
  CHECK(y[0] == Approx(t * t * t - t * t).epsilon(1e-14));
}

TEST_CASE("rk4 accumulate then finish gives combine's numbers to the bit", "[methods][rk4]") {
  // Values spread over many magnitudes and signs, where any reassociation would show.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> exponent(-12.0, 12.0), sign(-1.0, 1.0);
  auto draw = [&](Eigen::Index n) {
    Eigen::VectorXd v(n);
    for (Eigen::Index i = 0; i < n; ++i) v[i] = std::copysign(std::pow(10.0, exponent(random)), sign(random));
    return v;
  };
  const Eigen::Index n = 4000;
  const Eigen::VectorXd y0 = draw(n), k1 = draw(n), k2 = draw(n), k3 = draw(n), k4 = draw(n);
  for (const double h : {1e-3, 0.37, 7.0}) {
    Eigen::VectorXd combined = y0, folded = y0, sum = k1;
    rk4::combine(combined, k1, k2, k3, k4, h);
    rk4::accumulate(sum, k2);
    rk4::accumulate(sum, k3);
    rk4::finish(folded, sum, k4, h);
    CHECK(std::memcmp(combined.data(), folded.data(), sizeof(double) * static_cast<std::size_t>(n)) == 0);
    // and not by chance: a different order of the sums gives other bits somewhere
    Eigen::VectorXd other = y0;
    other += (h / 6.0) * (k4 + 2.0 * (k3 + k2) + k1);
    CHECK(std::memcmp(combined.data(), other.data(), sizeof(double) * static_cast<std::size_t>(n)) != 0);
  }
}
