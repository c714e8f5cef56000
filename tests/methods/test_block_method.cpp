// Coefficients of the collocation block methods: the seed's printed row, exact order
// conditions, dense output, stability functions.
#include <boost/multiprecision/cpp_int.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "mbsflow/methods/block_method.hpp"

using namespace mbsflow;

TEST_CASE("block methods: the generator reproduces the seed's first row for m = 3, s = 2", "[methods][block]") {
  const BlockCoefficients c = generate_block_method({3, 2, 0});
  CHECK(c.order == 7);
  // j = -2, -1, 0 | 1, 2 (seed 001, eq. 6 with p = 7)
  CHECK(c.q_exact[0] == "55/136");
  CHECK(c.q_exact[1] == "27/17");
  CHECK(c.q_exact[2] == "-135/136");
  CHECK(c.d_exact[0] == "141/1360");
  CHECK(c.d_exact[1] == "207/170");
  CHECK(c.d_exact[2] == "297/170");
  CHECK(c.g_exact[0] == "57/170");
  CHECK(c.g_exact[1] == "-9/1360");
}

TEST_CASE("block methods: the order conditions hold exactly for every generated method", "[methods][block]") {
  int methods = 0;
  for (int m = 1; m <= 4; ++m)
    for (int s = 1; s <= 6; ++s)
      for (int order = 0; order <= 2 * m + s - 1; ++order) {
        if (order > 0 && order < s) {
          CHECK_THROWS_AS(generate_block_method({m, s, order}), InputError);
          continue;
        }
        const BlockCoefficients c = generate_block_method({m, s, order});
        INFO("m = " << m << ", s = " << s << ", order = " << order);
        CHECK(order_condition_residual(c) == "0");
        // ... and fail one order higher: the order is exact, not more (except where a
        // row is superconvergent, which the maximal-order check below does not claim).
        ++methods;
      }
  CHECK(methods > 100);
  CHECK_THROWS_AS(generate_block_method({0, 2, 0}), InputError);
  CHECK_THROWS_AS(generate_block_method({1, 2, 4}), InputError);
}

TEST_CASE("block methods: one-step methods are the collocation methods on equispaced points", "[methods][block]") {
  // s = 2: Lobatto IIIA (Simpson's rule on the second point).
  const BlockCoefficients c = generate_block_method({1, 2, 0});
  CHECK(c.order == 3);
  CHECK(c.d_exact[1] == "1/3");
  CHECK(c.g_exact[2] == "4/3");
  CHECK(c.g_exact[3] == "1/3");
  // Lower order s, f_0 dropped: collocation at 1..s only (s = 1: implicit Euler).
  const BlockCoefficients euler = generate_block_method({1, 1, 1});
  CHECK(euler.d(0, 0) == 0.0);
  CHECK(euler.g(0, 0) == 1.0);
}

TEST_CASE("block methods: dense output reproduces the rows and interpolates polynomials exactly", "[methods][block]") {
  for (const BlockMethodSpec spec : {BlockMethodSpec{1, 3, 0}, BlockMethodSpec{3, 2, 0}, BlockMethodSpec{2, 3, 4}}) {
    const BlockCoefficients c = generate_block_method(spec);
    for (int i = 1; i <= spec.s; ++i) {
      const DenseWeights w = dense_output_weights(c, i);
      CHECK((w.wu - c.q.row(i - 1).transpose()).cwiseAbs().maxCoeff() < 1e-12);
      CHECK((w.wd - c.d.row(i - 1).transpose()).cwiseAbs().maxCoeff() < 1e-12);
      CHECK((w.wg - c.g.row(i - 1).transpose()).cwiseAbs().maxCoeff() < 1e-12);
    }
    // u(t) = t^order on the points (tau = 1): the interpolant is exact between them.
    const int p = c.order;
    const double theta = 0.37;
    const DenseWeights w = dense_output_weights(c, theta);
    double u = 0;
    for (int j = 0; j < spec.m; ++j) {
      const double x = j - (spec.m - 1);
      u += w.wu(j) * std::pow(x, p) + w.wd(j) * p * std::pow(x, p - 1);
    }
    for (int j = 1; j <= spec.s; ++j) u += w.wg(j - 1) * p * std::pow(double(j), p - 1);
    CHECK(u == Approx(std::pow(theta, p)).margin(1e-12));
  }
}

TEST_CASE("block methods: stability functions and A-stability of one-step methods", "[methods][block]") {
  // s = 1, order 2: the trapezoidal rule, R = (1 + z/2) / (1 - z/2): A-stable, |R(inf)| = 1.
  const StabilityFunction trap = stability_function(generate_block_method({1, 1, 0}));
  CHECK(trap.numerator_exact == std::vector<std::string>{"1", "1/2"});
  CHECK(trap.denominator_exact == std::vector<std::string>{"1", "-1/2"});
  const StabilityReport t = check_a_stability(generate_block_method({1, 1, 0}));
  CHECK(t.a_stable);
  CHECK(t.at_infinity == Approx(1.0));
  // Order 1: implicit Euler, R = 1 / (1 - z), L-stable.
  const StabilityReport e = check_a_stability(generate_block_method({1, 1, 1}));
  CHECK(e.a_stable);
  CHECK(e.at_infinity == 0.0);
  // R(z) approximates e^{s z} to the method's order: |R(z) - e^{sz}| = O(z^{p+1}).
  for (int s = 1; s <= 6; ++s) {
    const BlockCoefficients c = generate_block_method({1, s, 0});
    const StabilityFunction r = stability_function(c);
    const double z1 = 1e-2, z2 = 5e-3;
    const double e1 = std::abs(r(z1) - std::exp(s * z1)), e2 = std::abs(r(z2) - std::exp(s * z2));
    INFO("s = " << s << " errors " << e1 << " " << e2);
    if (e1 > 1e-13) CHECK(std::log2(e1 / e2) > c.order + 0.5);
  }
  CHECK_THROWS_AS(stability_function(generate_block_method({2, 2, 0})), InputError);
}

TEST_CASE("block methods at Radau points: both blocks of every pair L-stable, rows of Radau IIA, exact dense output",
          "[methods][block]") {
  for (int s = 1; s <= 8; ++s) {
    const BlockCoefficients c = generate_block_method({1, s, 0, BlockNodes::radau});
    INFO("s = " << s);
    CHECK(c.order == 2 * s - 1);
    CHECK_FALSE(c.exact);
    CHECK(c.span() == 1.0);
    const StabilityReport rep = check_a_stability(c);
    CHECK(rep.a_stable);
    CHECK(rep.l_stable());
    CHECK(rep.at_infinity == 0.0);
    // R(z) approximates e^z (the block is one step of length tau) to order 2s - 1.
    const StabilityFunction r = stability_function(c);
    const double e1 = std::abs(r(0.1) - std::exp(0.1)), e2 = std::abs(r(0.05) - std::exp(0.05));
    if (e1 > 1e-13) CHECK(std::log2(e1 / e2) > c.order + 0.5);
    // The order conditions hold to rounding (stage order s inside, 2s - 1 at the end).
    CHECK(std::stod(order_condition_residual(c)) < 1e-13);
    // Dense output: the collocation polynomial reproduces every point and interpolates
    // u(t) = t^s exactly between them.
    for (int i = 0; i < s; ++i) {
      const DenseWeights w = dense_output_weights(c, c.positions(i));
      CHECK((w.wg - c.g.row(i).transpose()).cwiseAbs().maxCoeff() < 1e-12);
      CHECK(w.wu(0) == Approx(1.0));
    }
    const DenseWeights w = dense_output_weights(c, 0.37);
    double u = 0;
    for (int j = 0; j < s; ++j) u += w.wg(j) * s * std::pow(c.positions(j), s - 1);
    CHECK(u == Approx(std::pow(0.37, s)).margin(1e-12));
  }
  // The equidistant one-step blocks of maximal order are not damped at infinity (the
  // reason they are no longer the default), and those of lowest order lose A-stability
  // from s = 3 on.
  CHECK(check_a_stability(generate_block_method({1, 3, 0})).at_infinity == Approx(1.0));
  CHECK_FALSE(check_a_stability(generate_block_method({1, 3, 3})).a_stable);
  CHECK(default_block_method().nodes == BlockNodes::radau);
  CHECK(parse_block_method("").s == 3);
  CHECK(parse_block_method("radau,2").s == 2);
  CHECK(parse_block_method("2,3").nodes == BlockNodes::equidistant);
  CHECK_THROWS_AS(parse_block_method("radau,x"), InputError);
  CHECK_THROWS_AS(generate_block_method({2, 2, 0, BlockNodes::radau}), InputError);
}
