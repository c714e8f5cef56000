// mbsflow bench ode: work-precision of the block methods and the triangularised Runge-Kutta
// methods (Radau IIA s = 3, every iteration scheme) against SUNDIALS CVODE (BDF with dense
// or band Newton) and Boost.Odeint (rk4, dopri5) on the seed's problems, in one run.
#include <boost/numeric/odeint.hpp>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>

#include "bench.hpp"
#include "cvode_driver.hpp"
#include "mbsflow/methods/block_integrator.hpp"
#include "mbsflow/methods/shifted_solver.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

namespace mbsflow::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct Outcome {
  bool ok = false;
  double seconds = 0, max_error = 0;
  long evaluations = 0, steps = 0;
  std::string note;
};

double error_at(const OdeProblem& p, double t, const double* y) {
  const Eigen::VectorXd e = p.exact(t);
  double m = 0;
  for (Eigen::Index i = 0; i < p.size; ++i) m = std::max(m, std::abs(y[i] - e(i)));
  return m;
}

// CVODE: BDF, Newton with the problem's exact Jacobian, band solver for banded systems.
Outcome run_cvode_bdf(const OdeProblem& p, double tol) {
  Outcome o;
  const CvodeLinearSolver solver = p.size > 100 ? CvodeLinearSolver::band : CvodeLinearSolver::dense;
  const CvodeOutcome c = run_cvode(p, tol, tol, solver, {}, [&](double t, const double* y) {
    o.max_error = std::max(o.max_error, error_at(p, t, y));
  });
  o.ok = c.ok;
  o.seconds = c.seconds;
  o.evaluations = c.evaluations;
  o.steps = c.steps;
  o.note = c.note;
  return o;
}

// Boost.Odeint, explicit: dopri5 with error control at tol, or rk4 with `steps` steps.
Outcome run_odeint(const OdeProblem& p, double tol, long rk4_steps) {
  namespace odeint = boost::numeric::odeint;
  using State = std::vector<double>;
  Outcome o;
  Eigen::VectorXd yv(p.size), fv(p.size);
  auto sys = [&](const State& x, State& dx, double t) {
    yv = Eigen::Map<const Eigen::VectorXd>(x.data(), p.size);
    p.evaluate(t, yv, fv);
    Eigen::Map<Eigen::VectorXd>(dx.data(), p.size) = fv;
    ++o.evaluations;
  };
  State x(p.y0.data(), p.y0.data() + p.size);
  auto observe = [&](const State& s, double t) { o.max_error = std::max(o.max_error, error_at(p, t, s.data())); ++o.steps; };
  const auto start = Clock::now();
  if (rk4_steps > 0) {
    odeint::integrate_n_steps(odeint::runge_kutta4<State>(), sys, x, p.t0, (p.t_end - p.t0) / rk4_steps, rk4_steps, observe);
  } else {
    odeint::integrate_adaptive(odeint::make_controlled(tol, tol, odeint::runge_kutta_dopri5<State>()), sys, x, p.t0, p.t_end,
                               1e-6, observe);
  }
  o.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  o.ok = std::isfinite(o.max_error) && o.max_error < 1e6;
  if (!o.ok) o.note = "unstable at this step";
  return o;
}

// Times one integration: `run` integrates (raising o.max_error on the way) and returns its
// statistics; an integration that fails keeps its message.
template <class Run>
Outcome timed(Run run) {
  Outcome o;
  const auto start = Clock::now();
  try {
    const auto stats = run(o);
    o.ok = true;
    o.evaluations = stats.rhs_evaluations;
    o.steps = stats.steps;
  } catch (const Error& e) {
    o.note = e.what();
  }
  o.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return o;
}

Outcome run_colloc(const OdeProblem& p, double tol, int s, int threads) {
  BlockSettings st;
  st.method = {1, s, 0};
  st.rtol = st.atol = tol;
  st.threads = threads;
  return timed([&](Outcome& o) {
    return integrate_block(p, st, [&](const AcceptedBlock& b) {
             for (int i = 0; i < b.points; ++i)
               o.max_error = std::max(o.max_error, error_at(p, b.t0 + (i + 1) * b.tau, (*b.u)[static_cast<std::size_t>(i)].data()));
           }).stats;
  });
}

// The triangularised Runge-Kutta methods (seed 004) with Radau IIA, 3 stages.
Outcome run_tirk(const OdeProblem& p, double tol, TirkIteration iteration, int threads) {
  TirkSettings st;
  st.tableau = "radau3";
  st.iteration = iteration;
  st.rtol = st.atol = tol;
  st.threads = threads;
  st.max_steps = 2'000'000;
  return timed([&](Outcome& o) {
    return integrate_tirk(p, st, [&](double t, const Eigen::VectorXd& y) { o.max_error = std::max(o.max_error, error_at(p, t, y.data())); })
        .stats;
  });
}

}  // namespace

int bench_ode(const BenchArgs& a) {
  const std::vector<std::string> problems =
      a.problems.empty() ? std::vector<std::string>{"hnw", "b1", "heat1000", "heat100000", "heat1000000"} : a.problems;
  const std::vector<double> tols = a.tolerances.empty() ? std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10} : a.tolerances;
  BenchCsv csv = open_csv(a);
  csv.out << "problem,n,solver,threads,tol,ok,seconds,max_error,rhs_evaluations,steps,note\n";
  std::printf("%-8s %8s %-22s %3s %7s %10s %10s %10s %8s\n", "problem", "N", "solver", "thr", "tol", "seconds", "max error",
              "f evals", "steps");
  for (const std::string& name : problems) {
    const OdeProblem p = builtin_problem(name, 4);
    if (!p.exact) throw InputError("bench ode: problem '" + name + "' has no exact solution (bench ivp runs it against its reference)");
    auto row = [&](const std::string& solver, int threads, double tol, const Outcome& o) {
      std::printf("%-8s %8ld %-22s %3d %7.0e %10.4f %10.3e %10ld %8ld %s\n", p.name.c_str(), long(p.size), solver.c_str(), threads,
                  tol, o.seconds, o.max_error, o.evaluations, o.steps, o.ok ? "" : ("failed: " + o.note).c_str());
      csv.out << p.name << ',' << p.size << ',' << solver << ',' << threads << ',' << tol << ',' << (o.ok ? 1 : 0) << ','
              << o.seconds << ',' << o.max_error << ',' << o.evaluations << ',' << o.steps << ",\"" << o.note << "\"\n";
      std::fflush(stdout);
    };
    for (std::size_t k = 0; k < tols.size(); ++k) {
      const double tol = tols[k];
      row(std::string("cvode-bdf-") + (p.size > 100 ? "band" : "dense"), 1, tol, run_cvode_bdf(p, tol));
      for (int s : {2, 3})
        for (int threads : {1, 2}) row("colloc-s" + std::to_string(s), threads, tol, run_colloc(p, tol, s, threads));
      for (TirkIteration it : {TirkIteration::newton_triangular, TirkIteration::newton_diagonal, TirkIteration::triangular,
                               TirkIteration::diagonal, TirkIteration::jacobi}) {
        if (!is_newton(it) && p.size > 100) continue;  // functional: the heat problem's contraction bound is out of reach
        for (int threads : {1, 2}) row(std::string("tirk-") + to_string(it), threads, tol, run_tirk(p, tol, it, threads));
      }
      if (p.size <= 100) {  // explicit methods: the heat problem's stability limit is out of reach
        row("odeint-dopri5", 1, tol, run_odeint(p, tol, 0));
        row("odeint-rk4", 1, tol, run_odeint(p, tol, 500L << (2 * k)));
      }
    }
  }
  std::printf("CSV: %s (work-precision plot: /usr/bin/python3 scripts/plot_work_precision.py %s)\n", csv.path.c_str(),
              csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
