// The tableaux and their triangular splitting: known nodes, quadrature and stage order,
// A = T_L T_U, the stiff limit of the triangular iteration, the embedded formula.
#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/methods/block_method.hpp"
#include "mbsflow/methods/rk_tableau.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

using namespace mbsflow;

TEST_CASE("tableaux: nodes of Radau IIA and Gauss in closed form", "[methods][tirk]") {
  const RkTableau r3 = rk_tableau("radau3");
  CHECK(r3.c(0) == Approx((4 - std::sqrt(6.0)) / 10).epsilon(1e-15));
  CHECK(r3.c(1) == Approx((4 + std::sqrt(6.0)) / 10).epsilon(1e-15));
  CHECK(r3.c(2) == 1.0);
  const RkTableau g2 = rk_tableau("gauss2");
  CHECK(g2.c(0) == Approx(0.5 - std::sqrt(3.0) / 6).epsilon(1e-15));
  CHECK(g2.c(1) == Approx(0.5 + std::sqrt(3.0) / 6).epsilon(1e-15));
  const RkTableau g3 = rk_tableau("gauss3");
  CHECK(g3.b(1) == Approx(4.0 / 9).epsilon(1e-15));
  CHECK(rk_tableau("radau2").a(0, 0) == Approx(5.0 / 12).epsilon(1e-15));
  CHECK(rk_tableau("radau4").order == 7);
  CHECK(quadrature_residual(rk_tableau("radau6"), 11) < 1e-14);
  CHECK_THROWS_AS(rk_tableau("radau13"), InputError);
  CHECK_THROWS_AS(rk_tableau("radau0"), InputError);
}

TEST_CASE("tableaux: quadrature to the order, stage order of the collocation methods", "[methods][tirk]") {
  for (const std::string& name : rk_tableau_names()) {
    INFO(name);
    const RkTableau t = rk_tableau(name);
    CHECK(quadrature_residual(t, t.order) < 1e-14);
    CHECK(quadrature_residual(t, t.order + 1) > 1e-6);  // and not one more
    CHECK((t.a * Eigen::VectorXd::Ones(t.stages()) - t.c).cwiseAbs().maxCoeff() < 1e-14);  // rows sum to c
  }
  for (const char* name : {"radau2", "radau3", "radau5", "gauss2", "gauss3"})
    CHECK(stage_order_residual(rk_tableau(name), rk_tableau(name).stages()) < 1e-13);
}

TEST_CASE("LDU: T_L T_U reproduces A, triangular shapes, the seed's L - I + D does not", "[methods][tirk]") {
  for (const std::string& name : rk_tableau_names()) {
    INFO(name);
    const RkTableau t = rk_tableau(name);
    const Eigen::MatrixXd a = t.implicit_block();
    const TriangularSplitting s = ldu_splitting(a);
    CHECK(s.reconstruction_error < 1e-14);
    CHECK((s.t_lower * s.t_upper - a).cwiseAbs().maxCoeff() < 1e-14);
    const Eigen::Index n = a.rows();
    for (Eigen::Index i = 0; i < n; ++i) {
      CHECK(s.l(i, i) == 1.0);
      CHECK(s.u(i, i) == 1.0);
      CHECK(s.t_lower(i, i) == s.d(i));
      for (Eigen::Index j = i + 1; j < n; ++j) {
        CHECK(s.t_lower(i, j) == 0.0);
        CHECK(s.t_upper(j, i) == 0.0);
      }
    }
    // The stiff limit of the triangular iteration, I - T_L^-1 A = I - T_U, is nilpotent.
    Eigen::MatrixXd z = Eigen::MatrixXd::Identity(n, n) - s.t_lower.inverse() * a, power = z;
    for (Eigen::Index k = 1; k < n; ++k) power = power * z;
    CHECK(power.cwiseAbs().maxCoeff() < 1e-12);
    if (n > 1) CHECK(s.seed_formula_error > 0.1);
  }
  Eigen::MatrixXd singular(2, 2);
  singular << 0, 1, 1, 0;
  CHECK_THROWS_AS(ldu_splitting(singular), InputError);
}

TEST_CASE("embedded formula: its order conditions hold and it differs from b", "[methods][tirk]") {
  for (const std::string& name : rk_tableau_names()) {
    INFO(name);
    const RkTableau t = rk_tableau(name);
    const EmbeddedFormula e = embedded_formula(t, ldu_splitting(t.implicit_block()));
    CHECK(e.order >= 1);
    CHECK(e.order < t.order);
    CHECK(e.gamma > 0);
    for (int k = 1; k <= e.order; ++k) {
      const double q = e.bhat.dot(t.c.array().pow(k - 1).matrix()) + (k == 1 ? e.gamma : 0.0);
      CHECK(q == Approx(1.0 / k).epsilon(1e-13));
    }
    CHECK((e.bhat - t.b).cwiseAbs().maxCoeff() > 1e-3);
    // All its order conditions, not only the quadrature ones: one step of the embedded
    // formula, x_n + tau (gamma f(x_n) + sum bhat_i F_i) with the method's own converged
    // stages, has a local error of order e.order + 1 on y' = -y^2 + t (y(0) = 1).
    auto f = [](double s, double y) { return -y * y + s; };
    auto local_error = [&](double tau) {
      // Exact solution at tau: a very fine RK4 reference.
      double y = 1.0;
      const int n = 4000;
      for (int k = 0; k < n; ++k) {
        const double h = tau / n, s = k * h;
        const double k1 = f(s, y), k2 = f(s + h / 2, y + h / 2 * k1), k3 = f(s + h / 2, y + h / 2 * k2), k4 = f(s + h, y + h * k3);
        y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      Eigen::VectorXd stage = Eigen::VectorXd::Ones(t.stages()), fs(t.stages());
      for (int it = 0; it < 200; ++it) {  // fixed-point iteration: contracts for these steps
        for (int i = 0; i < t.stages(); ++i) fs(i) = f(t.c(i) * tau, stage(i));
        stage = Eigen::VectorXd::Ones(t.stages()) + tau * t.a * fs;
      }
      for (int i = 0; i < t.stages(); ++i) fs(i) = f(t.c(i) * tau, stage(i));
      return std::abs(1.0 + tau * (e.gamma * f(0.0, 1.0) + e.bhat.dot(fs)) - y);
    };
    // Slopes between halved steps, where the error is above rounding: a missed condition
    // would leave at most slope e.order; the high orders reach theirs only at larger steps.
    double best = 0.0, previous = local_error(0.4);
    for (double tau : {0.2, 0.1, 0.05, 0.025}) {
      const double err = local_error(tau);
      if (err > 1e-13) best = std::max(best, std::log2(previous / err));
      previous = err;
    }
    CHECK(best > e.order + 1 - 0.3);
  }
}

TEST_CASE("contraction constants: Jacobi is the row-sum norm of A", "[methods][tirk]") {
  const RkTableau t = rk_tableau("radau3");
  const TriangularSplitting s = ldu_splitting(t.a);
  CHECK(contraction_constant(t.a, splitting_matrix(s, TirkIteration::jacobi)) ==
        Approx(t.a.cwiseAbs().rowwise().sum().maxCoeff()));
  CHECK(contraction_constant(t.a, splitting_matrix(s, TirkIteration::triangular)) >= t.a.cwiseAbs().rowwise().sum().maxCoeff());
  CHECK(tirk_iteration_from_string("newton-diagonal") == TirkIteration::newton_diagonal);
  CHECK_THROWS_AS(tirk_iteration_from_string("gauss-seidel"), InputError);
}

TEST_CASE("tableaux: stability reports (L-stable Radau IIA, Gauss not damped at infinity)", "[methods][tirk]") {
  for (int s = 1; s <= 7; ++s) {
    const RkTableau t = radau_iia(s);
    const StabilityReport r = check_a_stability(t);
    INFO(t.name);
    CHECK(r.l_stable());
    CHECK(stiffly_accurate(t));
    // R is the block method's at the same points.
    const StabilityFunction b = stability_function(generate_block_method({1, s, 0, BlockNodes::radau}));
    for (std::complex<double> z : {std::complex<double>(-3, 1), std::complex<double>(0.5, -2)})
      CHECK(std::abs(stability_value(t, z) - b(z)) < 1e-12);
  }
  const StabilityReport g = check_a_stability(rk_tableau("gauss3"));
  CHECK(g.a_stable);
  CHECK_FALSE(g.l_stable());
  CHECK(g.at_infinity == Approx(1.0));
  CHECK_FALSE(stiffly_accurate(rk_tableau("gauss3")));
  CHECK(check_a_stability(rk_tableau("lobatto3c")).l_stable());
  // R(z) = e^z + O(z^(p+1)) for every tableau.
  for (const std::string& name : rk_tableau_names()) {
    const RkTableau t = rk_tableau(name);
    const double e1 = std::abs(stability_value(t, 0.1) - std::exp(0.1)), e2 = std::abs(stability_value(t, 0.05) - std::exp(0.05));
    INFO(name << ": " << e1 << " " << e2);
    if (e1 > 1e-13) CHECK(std::log2(e1 / e2) > t.order + 0.5);
  }
}
