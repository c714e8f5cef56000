#include <catch2/catch.hpp>

#include "mbsflow/graph/force_table.hpp"

using namespace mbsflow;

TEST_CASE("force table: piecewise linear with linear extension", "[graph]") {
  const ForceTable t{{-1.0, 0.0, 1.0, 2.0}, {-3.0, 0.0, 1.0, 5.0}};
  CHECK(table_force(t, 0.5) == Approx(0.5));
  CHECK(table_force(t, 1.5) == Approx(3.0));
  CHECK(table_force(t, 3.0) == Approx(9.0));    // slope 4 beyond the last point
  CHECK(table_force(t, -2.0) == Approx(-6.0));  // slope 3 before the first
  CHECK(table_max_slope(t) == Approx(4.0));
}

TEST_CASE("force table energy is the integral of the force", "[graph]") {
  const ForceTable t{{-1.0, -0.2, 0.3, 1.0, 2.0}, {-2.0, -0.1, 0.4, 1.0, 5.0}};
  for (double x : {-2.5, -1.0, -0.5, 0.0, 0.1, 0.3, 0.7, 1.0, 1.9, 2.6}) {
    // Midpoint rule with many points is exact enough for a piecewise linear integrand.
    const int n = 20000;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += table_force(t, (i + 0.5) * x / n) * x / n;
    CHECK(table_energy(t, x) == Approx(sum).margin(1e-7));
  }
}

TEST_CASE("a joint's axis tables copy as values and reading an axis makes no tables", "[graph]") {
  const AxisTables none;
  CHECK_FALSE(none.any());
  CHECK(none[4].empty());
  CHECK(std::distance(none.begin(), none.end()) == 6);
  AxisTables a;
  a[1] = ForceTable{{-1.0, 0.0, 1.0}, {-2.0, 0.0, 3.0}};
  CHECK(a.any());
  AxisTables b = a;  // deep: changing the copy leaves the original
  b[1].force[2] = 5.0;
  CHECK(a[1].force[2] == 3.0);
  CHECK(b[1].force[2] == 5.0);
  CHECK(b[0].empty());
  AxisTables c;
  c = none;
  CHECK_FALSE(c.any());
  c = a;
  CHECK(c[1].deflection == a[1].deflection);
  const AxisTables moved = std::move(c);
  CHECK(moved.any());
}
