#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/line_fit.hpp"

using namespace mbsflow;

namespace {
// Kepler orbit with eccentricity 0.6: a standard non-stiff test with a known period 2 pi.
auto kepler() {
  return make_system(4, [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    const double r3 = std::pow(y[0] * y[0] + y[1] * y[1], 1.5);
    dy << y[2], y[3], -y[0] / r3, -y[1] / r3;
  });
}
Eigen::VectorXd kepler_start() {
  const double e = 0.6;
  Eigen::VectorXd y(4);
  y << 1 - e, 0, 0, std::sqrt((1 + e) / (1 - e));
  return y;
}

struct Result {
  double error;
  long steps, rejected;
};

Result integrate(double tol) {
  auto sys = kepler();
  Dopri5Settings s;
  s.rtol = s.atol = tol;
  Dopri5 dp(4, s);
  Eigen::VectorXd y = kepler_start();
  const double t_end = 2 * M_PI;
  double t = 0.0, h = dp.initial_step(sys, t, y), taken = 0.0;
  while (t < t_end) {
    h = std::min(h, t_end - t);
    REQUIRE(dp.step(sys, t, h, y, taken));
    t = (t_end - (t + taken) < 1e-14) ? t_end : t + taken;
  }
  return {(y - kepler_start()).norm(), dp.stats().accepted, dp.stats().rejected};
}
}  // namespace

TEST_CASE("DOPRI5 error scales with the tolerance", "[methods]") {
  std::vector<double> tols, errs;
  for (double tol : {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}) {
    const Result r = integrate(tol);
    tols.push_back(tol);
    errs.push_back(r.error);
    INFO("tol " << tol << ": error " << r.error << ", " << r.steps << " steps, " << r.rejected << " rejected");
    CHECK(r.error < 1e4 * tol);
  }
  for (std::size_t i = 1; i < errs.size(); ++i) CHECK(errs[i] < errs[i - 1]);
  const double slope = log_log_slope(tols, errs);
  INFO("d log(error) / d log(tol) = " << slope);
  CHECK(slope > 0.8);
  CHECK(slope < 1.2);
}

TEST_CASE("DOPRI5 steps grow with tolerance like tol^(1/5)", "[methods]") {
  const Result loose = integrate(1e-6), tight = integrate(1e-9);
  const double ratio = static_cast<double>(tight.steps) / static_cast<double>(loose.steps);
  CHECK(ratio == Approx(std::pow(1e3, 0.2)).epsilon(0.25));
}

TEST_CASE("DOPRI5 dense output is accurate inside each step", "[methods]") {
  auto sys = make_system(1, [](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) { dy[0] = y[0] * std::cos(t); });
  Dopri5Settings s;
  s.rtol = s.atol = 1e-9;
  Dopri5 dp(1, s);
  Eigen::VectorXd y = Eigen::VectorXd::Constant(1, 1.0), out(1);
  double t = 0.0, h = 0.1, taken = 0.0, max_err = 0.0;
  while (t < 5.0) {
    REQUIRE(dp.step(sys, t, h, y, taken));
    for (double th : {0.1, 0.37, 0.5, 0.81}) {
      dp.dense(t + th * taken, out);
      max_err = std::max(max_err, std::abs(out[0] - std::exp(std::sin(t + th * taken))));
    }
    dp.dense(t + taken, out);
    CHECK(out[0] == Approx(y[0]).epsilon(1e-15));
    t += taken;
  }
  INFO("dense output error " << max_err);
  CHECK(max_err < 1e-7);
}

TEST_CASE("DOPRI5 rejects steps across a fast transient and reports a collapsed step", "[methods]") {
  auto sys = make_system(1, [](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    dy[0] = -50.0 * (y[0] - std::cos(t));
  });
  Dopri5 dp(1);
  Eigen::VectorXd y = Eigen::VectorXd::Constant(1, 0.0);
  double t = 0.0, h = 1.0, taken = 0.0;
  REQUIRE(dp.step(sys, t, h, y, taken));
  CHECK(dp.stats().rejected > 0);
  Dopri5Settings tiny;
  tiny.h_min = 1.0;  // any step this problem needs is smaller
  Dopri5 strict(1, tiny);
  double h2 = 2.0;
  y[0] = 0.0;
  CHECK_FALSE(strict.step(sys, 0.0, h2, y, taken));
}
