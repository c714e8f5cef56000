#include <catch2/catch.hpp>
#include <cmath>

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
