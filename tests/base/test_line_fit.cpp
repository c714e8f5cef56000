#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/line_fit.hpp"

using mbsflow::line_fit;

TEST_CASE("line fit: points on a line give its slope and intercept back") {
  const std::vector<double> x{-1.0, 0.5, 2.0, 7.0};
  std::vector<double> y;
  for (double xi : x) y.push_back(3.0 - 0.25 * xi);
  const auto f = line_fit(x, y);
  CHECK(f.slope == Approx(-0.25).epsilon(1e-14));
  CHECK(f.intercept == Approx(3.0).epsilon(1e-14));
}

TEST_CASE("line fit: noise symmetric about a line leaves the line") {
  // Residuals +e, -e, -e, +e at symmetric x are orthogonal to 1 and x.
  const std::vector<double> x{0, 1, 2, 3}, y{1 + 0.1, 3 - 0.1, 5 - 0.1, 7 + 0.1};
  const auto f = line_fit(x, y);
  CHECK(f.slope == Approx(2.0).epsilon(1e-14));
  CHECK(f.intercept == Approx(1.0).epsilon(1e-14));
}

TEST_CASE("log-log slope: the exponent of a power law") {
  const std::vector<double> x{1e-3, 1e-2, 0.5, 4.0};
  std::vector<double> y;
  for (double xi : x) y.push_back(7.0 * std::pow(xi, 3.5));
  CHECK(mbsflow::log_log_slope(x, y) == Approx(3.5).epsilon(1e-12));
}
