// Integration with the triangularised Runge-Kutta methods: order of every tableau with
// converged iterations, the contraction bound of the functional iterations, Newton-type
// iterations on a large stiff system, bitwise identity of parallel and sequential runs,
// and the iteration trace.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <vector>

#include "mbsflow/line_fit.hpp"
#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

using namespace mbsflow;

namespace {

double fixed_step_slope(const OdeProblem& p, TirkSettings s, const std::vector<int>& steps) {
  std::vector<double> h, e;
  for (int n : steps) {
    s.fixed_step = (p.t_end - p.t0) / n;
    const TirkResult r = integrate_tirk(p, s);
    h.push_back(s.fixed_step);
    e.push_back((r.y - p.exact(r.t)).cwiseAbs().maxCoeff());
  }
  return mbsflow::log_log_slope(h, e);
}

double infinity_norm(const OdeProblem& p) {
  Eigen::SparseMatrix<double> j = *p.sparsity;
  p.jacobian(p.t0, p.y0, j);
  return mbsflow::infinity_norm(j);
}

}  // namespace

TEST_CASE("tirk: every tableau reaches its order with converged iterations (eq. 10 on [0, 1])", "[methods][tirk]") {
  OdeProblem p = hairer_wanner_problem();
  p.t_end = 1;
  // Steps in each method's asymptotic range, above rounding.
  const std::map<std::string, std::vector<int>> steps = {
      {"radau2", {16, 32, 64}},  {"radau3", {16, 24, 32}},    {"radau5", {15, 16, 17}}, {"gauss2", {16, 32, 64}},
      {"gauss3", {16, 24, 32}},  {"lobatto3c", {32, 64, 128}}, {"block1", {8, 16, 32}},  {"block2", {8, 16, 32}},
      {"block3", {8, 16, 32}},   {"block4", {16, 24, 32}},    {"block5", {16, 24, 32}}, {"block6", {12, 16, 24}}};
  for (const auto& [name, n] : steps)
    for (TirkIteration it : {TirkIteration::newton_triangular, TirkIteration::newton}) {
      TirkSettings s;
      s.tableau = name;
      s.iteration = it;
      s.fixed_iterations = 40;  // converged: the simplified Newton iterations contract at these steps
      s.threads = 1;
      const double slope = fixed_step_slope(p, s, n);
      INFO(name << " " << to_string(it) << ": slope " << slope);
      CHECK(std::abs(slope - rk_tableau(name).order) <= 0.3);
    }
}

TEST_CASE("tirk: the functional iterations converge within tau < 1/(L M) and diverge far outside", "[methods][tirk]") {
  OdeProblem p = heat_problem(30);  // linear: L = |J|_inf is a Lipschitz constant in the max norm
  p.t_end = 0.02;
  const double l = infinity_norm(p);
  for (TirkIteration it : {TirkIteration::jacobi, TirkIteration::triangular, TirkIteration::diagonal}) {
    TirkSettings s;
    s.iteration = it;
    s.threads = 1;
    const TriangularSplitting split = ldu_splitting(rk_tableau(s.tableau).a);
    const double m = contraction_constant(rk_tableau(s.tableau).a, splitting_matrix(split, it));
    INFO(to_string(it) << ": L = " << l << ", M = " << m);
    s.fixed_step = 0.5 / (l * m);
    const TirkResult ok = integrate_tirk(p, s);
    CHECK(ok.stats.iteration_failures == 0);
    CHECK(ok.stats.contraction_m == Approx(m));
    CHECK(ok.stats.lipschitz_start == Approx(l));
    CHECK(ok.stats.lipschitz_observed <= l * (1 + 1e-12));
    CHECK((ok.y - p.exact(ok.t)).cwiseAbs().maxCoeff() < 1e-6);
    s.fixed_step = 40 / (l * m);
    try {
      integrate_tirk(p, s);
      FAIL("no divergence reported");
    } catch (const RunError& e) {
      CHECK_THAT(e.what(), Catch::Contains("diverged") && Catch::Contains("tau < 1/(L M)"));
    }
  }
}

TEST_CASE("tirk: Newton-type iterations solve heat with N = 1e5 at large steps", "[methods][tirk][slow]") {
  const OdeProblem p = heat_problem(100000);
  const double explicit_limit = 2.0 / infinity_norm(p);
  for (auto [tableau, it] : {std::pair{"radau3", TirkIteration::newton_triangular}, std::pair{"radau2", TirkIteration::newton_diagonal},
                             std::pair{"radau3", TirkIteration::newton}}) {
    TirkSettings s;
    s.tableau = tableau;
    s.iteration = it;
    s.rtol = s.atol = 1e-5;
    double err = 0;
    const TirkResult r = integrate_tirk(p, s, [&](double t, const Eigen::VectorXd& y) {
      err = std::max(err, (y - p.exact(t)).cwiseAbs().maxCoeff());
    });
    INFO(tableau << " " << to_string(it) << ": steps " << r.stats.steps << ", largest " << r.stats.largest_step << ", error " << err);
    CHECK(r.t == p.t_end);
    CHECK(err <= 1e-4);
    CHECK(r.stats.largest_step > 1e8 * explicit_limit);
    CHECK(r.stats.steps < 400);
  }
}

TEST_CASE("tirk: step control keeps the error near the tolerance and follows it", "[methods][tirk]") {
  const OdeProblem p = detest_b1_problem();
  std::vector<double> errors;
  for (double tol : {1e-5, 1e-7}) {
    TirkSettings s;
    s.rtol = s.atol = tol;
    s.threads = 1;
    double err = 0;
    const TirkResult r = integrate_tirk(p, s, [&](double t, const Eigen::VectorXd& y) {
      err = std::max(err, (y - p.exact(t)).cwiseAbs().maxCoeff());
    });
    INFO("tol " << tol << ": error " << err << ", rejected " << r.stats.rejected);
    CHECK(err <= 100 * tol);
    errors.push_back(err);
  }
  CHECK(errors[1] < errors[0] / 10);
}

TEST_CASE("tirk: parallel and sequential runs give bitwise the same numbers", "[methods][tirk]") {
  for (TirkIteration it : {TirkIteration::newton_triangular, TirkIteration::newton_diagonal, TirkIteration::triangular,
                           TirkIteration::jacobi, TirkIteration::newton}) {
    OdeProblem p = heat_problem(20000);
    TirkSettings s;
    s.iteration = it;
    s.slice_size = 1500;  // 14 slices per stage
    if (is_newton(it)) {
      s.rtol = s.atol = 1e-6;
    } else {  // a short stretch at a step inside the functional iterations' range
      s.fixed_step = 0.5 / infinity_norm(p);
      p.t_end = 6 * s.fixed_step;
    }
    std::vector<TirkResult> runs;
    for (int threads : {1, 2, 4}) {
      s.threads = threads;
      runs.push_back(integrate_tirk(p, s));
    }
    INFO(to_string(it));
    REQUIRE(runs[0].steps.size() > 3);
    for (std::size_t k = 1; k < runs.size(); ++k) {
      CHECK((runs[0].y.array() == runs[k].y.array()).all());
      REQUIRE(runs[0].steps.size() == runs[k].steps.size());
      for (std::size_t i = 0; i < runs[0].steps.size(); ++i) {
        CHECK(runs[0].steps[i].tau == runs[k].steps[i].tau);
        CHECK(runs[0].steps[i].iterations_s == runs[k].steps[i].iterations_s);
      }
    }
  }
}

TEST_CASE("tirk: the iteration trace converges to the stage values the integrator uses", "[methods][tirk]") {
  const OdeProblem p = detest_b1_problem();
  TirkSettings s;
  s.threads = 1;
  for (TirkIteration it : {TirkIteration::jacobi, TirkIteration::triangular, TirkIteration::newton_triangular,
                           TirkIteration::newton}) {
    s.iteration = it;
    const IterationTrace tr = trace_tirk_iterations(p, s, 10.0, p.exact(10.0), 1e-4, 6);
    INFO(to_string(it));
    REQUIRE(tr.reference_ok);
    CHECK(tr.reference_residual < 1e-14);
    CHECK(tr.error[0] > 0);
    if (it == TirkIteration::newton)
      CHECK(tr.error[1] <= 1e-13);  // the full Newton iteration: quadratic, at rounding after two
    else
      CHECK(tr.error[3] < 1e-3 * tr.error[0]);
    CHECK(tr.evaluations[1] == 2 * tr.evaluations[0]);
  }
  // Non-stiff regime: the triangular splitting gains on the diagonal one and on Jacobi
  // after the first iteration (rho(A - T_L) < rho(A - D) < rho(A) for Radau IIA).
  auto first = [&](TirkIteration it) {
    s.iteration = it;
    return trace_tirk_iterations(p, s, 10.0, p.exact(10.0), 1e-4, 1).error[0];
  };
  CHECK(first(TirkIteration::triangular) < first(TirkIteration::diagonal));
  CHECK(first(TirkIteration::diagonal) < first(TirkIteration::jacobi));
}

TEST_CASE("tirk newton: matrices kept across small step changes, same accuracy, fewer factorisations", "[methods][tirk]") {
  const OdeProblem p = hairer_wanner_problem();
  std::vector<TirkResult> runs;
  for (double ratio : {0.0, 0.2}) {
    TirkSettings s;
    s.iteration = TirkIteration::newton;
    s.rtol = s.atol = 1e-6;
    s.refactor_ratio = ratio;
    s.threads = 1;
    runs.push_back(integrate_tirk(p, s));
    const TirkResult& r = runs.back();
    // The error in units of the tolerance (atol + rtol |y|: x2 reaches 148).
    const Eigen::VectorXd y = p.exact(r.t);
    const double err = ((r.y - y).array().abs() / (s.atol + s.rtol * y.array().abs())).maxCoeff();
    INFO("refactor_ratio " << ratio << ": " << r.stats.steps << " steps, " << r.stats.factorizations
                           << " factorisations, error " << err << " tolerances");
    CHECK(err <= 10);  // within a small factor of the tolerance
    CHECK(r.stats.factorizations % 2 == 0);  // radau3: one real and one complex system per factorisation
  }
  CHECK(runs[1].stats.factorizations < runs[0].stats.factorizations);
  TirkSettings bad;
  bad.refactor_ratio = 1.5;
  CHECK_THROWS_AS(integrate_tirk(p, bad), InputError);
}

TEST_CASE("tirk newton: f only at the iterates it corrects (no predictor or converged-iterate evaluations)", "[methods][tirk]") {
  // As Radau5: each iteration evaluates f at its iterate and corrects it, so the last
  // (converged) iterate is never evaluated and the step takes its K_j from the stage
  // values; f(x_{n+1}) is evaluated once per step for the next. With a fixed step and a
  // fixed iteration count the right-hand sides are 1 + N (s k + 1) exactly, the Jacobian
  // being analytic; the result still has the method's order (for a stiffly accurate
  // tableau and for Gauss, whose step end sums the K_j).
  OdeProblem p = hairer_wanner_problem();
  p.t_end = 1;
  for (const char* name : {"radau3", "gauss3"}) {
    TirkSettings s;
    s.tableau = name;
    s.iteration = TirkIteration::newton;
    s.fixed_iterations = 4;
    s.threads = 1;
    const int n = 32;
    s.fixed_step = 1.0 / n;
    const TirkResult r = integrate_tirk(p, s);
    const int stages = rk_tableau(name).stages();
    INFO(name << ": " << r.stats.rhs_evaluations << " right-hand sides, " << r.stats.jacobians << " Jacobians");
    CHECK(r.stats.iterations == 4L * n);
    CHECK(r.stats.rhs_evaluations == 1 + n * (stages * 4L + 1));
    s.fixed_iterations = 40;
    CHECK(std::abs(fixed_step_slope(p, s, {16, 24, 32}) - rk_tableau(name).order) <= 0.3);
  }
}
