// mbsflow ode --method tirk: the triangularised implicit Runge-Kutta methods (seed 004).
#include "mbsflow/methods/real_eigen.hpp"
#include <chrono>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"
#include "ode_common.hpp"

namespace mbsflow::cli {
namespace {

void print_matrix(const char* name, const Eigen::MatrixXd& m) {
  std::printf("%s =\n", name);
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    std::printf("   ");
    for (Eigen::Index j = 0; j < m.cols(); ++j) std::printf(" %12.8f", m(i, j));
    std::printf("\n");
  }
}

double spectral_radius(const Eigen::MatrixXd& m) { return eigenvalues_of(m).cwiseAbs().maxCoeff(); }

TirkIteration iteration_of(const OdeArgs& a) {
  return a.iteration.empty() ? TirkIteration::newton : tirk_iteration_from_string(a.iteration);
}

}  // namespace

int describe_tableau(const std::string& name) {
  const RkTableau t = rk_tableau(name);
  const TriangularSplitting sp = ldu_splitting(t.implicit_block());
  const EmbeddedFormula e = embedded_formula(t, sp);
  const Eigen::MatrixXd a = t.implicit_block(), id = Eigen::MatrixXd::Identity(a.rows(), a.cols());
  std::printf("%s: %s, %d stages, order %d%s\n", t.name.c_str(), t.family.c_str(), t.stages(), t.order,
              t.explicit_first ? " (stage 1 explicit: K_1 = f(t_n, x_n))" : "");
  std::printf("quadrature check |sum b_i c_i^(k-1) - 1/k|, k <= %d: %.2e\n", t.order, quadrature_residual(t, t.order));
  const StabilityReport st = check_a_stability(t);
  std::printf("stability: R(z) = 1 + z b^T (I - z A)^-1 1; max |R(iy)| = %.4g, |R(inf)| = %.3g, smallest Re(pole) = %.4g: %s%s\n",
              st.max_on_imaginary_axis, st.at_infinity, st.min_pole_real_part,
              stability_verdict(st),
              stiffly_accurate(t) ? ", stiffly accurate" : ", not stiffly accurate (the step's end is not its last stage)");
  print_matrix("A", t.a);
  print_matrix("b", t.b.transpose());
  print_matrix("c", t.c.transpose());
  std::printf("LDU of the implicit block (%d x %d), no pivoting:\n", int(a.rows()), int(a.cols()));
  print_matrix("L", sp.l);
  print_matrix("D (diagonal approximation)", sp.d.transpose());
  print_matrix("U = T_U", sp.u);
  print_matrix("T_L = L D", sp.t_lower);
  std::printf("max |T_L T_U - A| = %.2e; the seed's T_L = L - I + D gives max |(L - I + D) U - A| = %.3g\n", sp.reconstruction_error,
              sp.seed_formula_error);
  std::printf("embedded formula: gamma = %.6f on f(t_n, x_n), order %d; bhat =", e.gamma, e.order);
  for (Eigen::Index i = 0; i < e.bhat.size(); ++i) std::printf(" %.8f", e.bhat(i));
  std::printf("\n\n%-18s %8s %18s %18s\n", "iteration", "M", "rho(A - T)", "rho(I - T^-1 A)");
  std::printf("%-18s %8s %18s %18s\n", "", "(bound)", "(non-stiff rate/z)", "(stiff limit)");
  for (TirkIteration it : {TirkIteration::jacobi, TirkIteration::triangular, TirkIteration::diagonal}) {
    const Eigen::MatrixXd tm = splitting_matrix(sp, it);
    const double stiff = it == TirkIteration::jacobi ? std::numeric_limits<double>::infinity() : spectral_radius(id - tm.inverse() * a);
    std::printf("%-18s %8.4f %18.4f %18.4g\n", to_string(it), contraction_constant(a, tm), spectral_radius(a - tm), stiff);
  }
  std::printf("functional iterations contract for tau < 1/(L M), L the Lipschitz constant of f; the Newton-type ones\n"
              "(newton-triangular, newton-diagonal) converge on very stiff components when rho(I - T^-1 A) < 1.\n");
  // The full Newton iteration: one linear system per real eigenvalue or complex pair of A.
  const Eigen::VectorXcd mu = eigenvalues_of(a);
  std::printf("\nnewton (default): the full simplified Newton iteration, one system per real eigenvalue or complex pair of A:");
  for (Eigen::Index i = 0; i < mu.size(); ++i)
    if (mu(i).imag() >= 0) std::printf(mu(i).imag() > 1e-12 ? " %.6f+-%.6fi" : " %.6f", mu(i).real(), mu(i).imag());
  const double g0 = largest_real_eigenvalue(t);
  if (g0 > 0) std::printf("\n  its error estimate filters through the real system, gamma = %.6f\n", g0);
  else std::printf("\n  no real eigenvalue: its error estimate factorises I - tau gamma J with gamma = %.6f\n", e.gamma);
  return 0;
}

int run_tirk(const OdeArgs& a) {
  OdeProblem p;
  TirkSettings s;
  RkTableau tab;
  try {
    p = builtin_problem(a.problem, a.n);
    s.tableau = a.tableau;
    tab = rk_tableau(a.tableau);
    s.iteration = iteration_of(a);
    apply_common_options(a, p, s);
  } catch (const InputError& e) {
    throw InputError(std::string("ode: ") + e.what());
  }
  s.fixed_iterations = a.iterations;
  s.inner_iterations = a.inner;
  OdeRecorder rec(p, !a.output.empty());
  if (!a.quiet)
    std::cerr << "mbsflow ode: " << p.name << " (N = " << p.size << ") on [" << p.t0 << ", " << p.t_end << "], tirk " << tab.name
              << " (order " << tab.order << "), " << to_string(s.iteration) << ", tol " << a.tol << "\n";
  const auto start = std::chrono::steady_clock::now();
  TirkResult r;
  try {
    r = integrate_tirk(p, s, [&](double t, const Eigen::VectorXd& y) { rec.add(t, y); });
  } catch (const InputError& e) {
    throw InputError(std::string("ode: ") + e.what());
  } catch (const RunError& e) {
    throw RunError(std::string("ode: ") + e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const TirkStats& st = r.stats;
  std::printf("steps %ld (accepted %ld, rejected %ld, of which %ld by the iteration), largest step %.4g\n", st.steps, st.accepted,
              st.rejected, st.iteration_failures, st.largest_step);
  std::printf("rhs evaluations %ld, iterations %ld (%.2f per step), Jacobians %ld, factorizations %ld (%s)\n", st.rhs_evaluations,
              st.iterations, st.steps ? double(st.iterations) / double(st.steps) : 0.0, st.jacobians, st.factorizations,
              is_newton(s.iteration) ? to_string(st.linear_solver) : "none");
  if (!is_newton(s.iteration)) {
    const double l = std::max(st.lipschitz_start, st.lipschitz_observed);
    std::printf("contraction bound tau < 1/(L M): M = %.4f, L >= %.4g (|J(t0, y0)|_inf %.4g, iterates %.4g): tau < %.4g\n",
                st.contraction_m, l, st.lipschitz_start, st.lipschitz_observed, l > 0 ? 1.0 / (l * st.contraction_m) : INFINITY);
  }
  if (p.exact) std::printf("max error %.3e (against the exact solution, all accepted steps)\n", rec.max_error());
  report_end_error(p, r.y);
  rec.warn_uncontrolled(s.atol, s.atols);
  std::printf("wall time %.3f s\n", seconds);
  rec.write(a.output, r.steps, {{"problem", p.name}, {"method", "tirk"}, {"tableau", tab.name}, {"iteration", to_string(s.iteration)}},
            {{"n", double(p.size)}, {"s", double(tab.stages())}, {"order", double(tab.order)}, {"tol", a.tol}, {"wall_seconds", seconds},
             {"rhs_evaluations", double(st.rhs_evaluations)}, {"contraction_m", st.contraction_m}},
            a.quiet);
  return 0;
}

}  // namespace mbsflow::cli
