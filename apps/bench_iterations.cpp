// mbsflow bench iterations: the measurement of seed 004's claim. One step from the middle
// of each problem (x = the exact solution there), iterated 1, 2, ... times from the
// trivial predictor with each scheme; the distance of the stage values to the converged
// ones after each iteration, for steps from a fraction to many times the contraction
// bound of the Jacobi iteration.
#include <cmath>
#include <cstdio>

#include "bench.hpp"
#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

namespace mbsflow::cli {
namespace {

struct Scheme {
  const char* label;
  TirkIteration iteration;
  int inner;
};

}  // namespace

int bench_iterations(const BenchArgs& a) {
  const std::vector<std::string> problems = a.problems.empty() ? std::vector<std::string>{"hnw", "b1", "heat200"} : a.problems;
  const std::string tableau = a.tableau.empty() ? "radau3" : a.tableau;
  const int count = 8;
  const std::vector<double> factors = {0.1, 0.5, 2, 10, 100, 10000};
  const std::vector<Scheme> schemes = {{"jacobi", TirkIteration::jacobi, 1},
                                       {"triangular", TirkIteration::triangular, 3},
                                       {"diagonal", TirkIteration::diagonal, 3},
                                       {"triangular-inner1", TirkIteration::triangular, 1},
                                       {"newton-triangular", TirkIteration::newton_triangular, 1},
                                       {"newton-diagonal", TirkIteration::newton_diagonal, 1}};
  BenchCsv csv = open_csv(a);
  csv.out << "problem,n,tableau,tau,tau_over_jacobi_bound,scheme,iteration,error,rhs_evaluations\n";
  const RkTableau tab = rk_tableau(tableau);
  const double m_jacobi = contraction_constant(tab.implicit_block(), Eigen::MatrixXd::Zero(tab.implicit_stages(), tab.implicit_stages()));
  std::printf("tableau %s; error = max |Y^nu - Y*| / max(1, |Y*|) after iteration nu; bound = 1/(L M_jacobi), L = |J|_inf at the start\n",
              tab.name.c_str());
  for (const std::string& name : problems) {
    const OdeProblem p = builtin_problem(name, 4);
    if (!p.exact) throw InputError("bench iterations: problem '" + name + "' has no exact solution (bench ivp runs it against its reference)");
    const double t = 0.5 * (p.t0 + p.t_end);
    const Eigen::VectorXd x = p.exact(t);
    Eigen::SparseMatrix<double> j = *p.sparsity;
    p.jacobian(t, x, j);
    const double l = infinity_norm(j), bound = 1.0 / (l * m_jacobi);
    std::printf("\n%s (N = %ld) from t = %g: L = %.4g, Jacobi bound tau < %.4g\n", p.name.c_str(), long(p.size), t, l, bound);
    std::printf("%-10s %-18s", "tau/bound", "scheme");
    for (int k = 1; k <= count; ++k) std::printf("   nu=%-3d", k);
    std::printf("  f/iter\n");
    for (double factor : factors) {
      const double tau = factor * bound;
      if (tau > p.t_end - t) continue;
      for (const Scheme& sc : schemes) {
        TirkSettings s;
        s.tableau = tableau;
        s.iteration = sc.iteration;
        s.inner_iterations = sc.inner;
        s.threads = 1;
        const IterationTrace tr = trace_tirk_iterations(p, s, t, x, tau, count);
        std::printf("%-10g %-18s", factor, sc.label);
        for (int k = 0; k < count; ++k) {
          std::printf(" %8.1e", tr.error[static_cast<std::size_t>(k)]);
          csv.out << p.name << ',' << p.size << ',' << tableau << ',' << tau << ',' << factor << ',' << sc.label << ',' << k + 1 << ','
                  << tr.error[static_cast<std::size_t>(k)] << ',' << tr.evaluations[static_cast<std::size_t>(k)] << '\n';
        }
        std::printf("  %ld%s\n", tr.evaluations[0], tr.reference_ok ? "" : "  (no converged reference)");
      }
    }
  }
  std::printf("\nCSV: %s (plot: /usr/bin/python3 scripts/plot_iterations.py %s)\n", csv.path.c_str(), csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
