// mbsflow ode: the seed's test problems (and their methods) from the command line.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "commands.hpp"
#include "ode_common.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/ode_results.hpp"
#include "mbsflow/methods/block_integrator.hpp"

namespace mbsflow::cli {
namespace {

std::string join(const std::vector<std::string>& v, std::size_t row, std::size_t width) {
  std::string out;
  for (std::size_t j = 0; j < width; ++j) out += (j ? ", " : "") + v[row * width + j];
  return out;
}

std::string polynomial(const std::vector<std::string>& c) {
  std::string out;
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (c[k] == "0") continue;
    out += (out.empty() ? "" : " + ") + ("(" + c[k] + ")") + (k == 0 ? "" : k == 1 ? " z" : " z^" + std::to_string(k));
  }
  return out.empty() ? "0" : out;
}

BlockMethodSpec spec_of(const OdeArgs& a) {
  const bool radau = a.nodes == "radau" || (a.nodes.empty() && a.m == 1 && a.order == 0);
  BlockMethodSpec spec{a.m, a.s, a.order, radau ? BlockNodes::radau : BlockNodes::equidistant};
  generate_block_method(spec);  // InputError for a method that does not exist
  return spec;
}

void print_stability(const StabilityReport& rep) {
  std::cout << "  max |R(iy)| = " << rep.max_on_imaginary_axis << ", |R(inf)| = " << rep.at_infinity
            << ", smallest Re(pole) = " << rep.min_pole_real_part << ": " << stability_verdict(rep) << "\n";
}

int describe(const OdeArgs& a) {
  const BlockMethodSpec spec = spec_of(a);
  const BlockCoefficients c = generate_block_method(spec);
  std::cout << "collocation block method (" << to_string(spec.nodes) << " points): m = " << a.m << " steps, s = " << a.s
            << " points, order " << c.order << " (maximal " << c.spec.maximal_order() << ")\n"
            << "u_i = sum_j q_ij u_j + tau (sum_j d_ij f_j + sum_j g_ij f_j), past points j = " << -(a.m - 1)
            << "..0, block points at t0 + p_j tau, p = (";
  for (Eigen::Index j = 0; j < c.positions.size(); ++j) std::cout << (j ? ", " : "") << c.positions(j);
  std::cout << ")\n";
  for (int i = 0; i < a.s; ++i)
    std::cout << "  i = " << i + 1 << ": q = (" << join(c.q_exact, i, a.m) << "), d = (" << join(c.d_exact, i, a.m)
              << "), g = (" << join(c.g_exact, i, a.s) << ")\n";
  std::cout << "order conditions: largest " << (c.exact ? "exact" : "rounded") << " residual " << order_condition_residual(c)
            << "\n";
  if (a.m == 1) {
    const StabilityFunction r = stability_function(c);
    std::cout << "stability function R(z) = P(z)/Q(z), z = lambda tau, u_s = R(z) u_0\n"
              << "  P(z) = " << polynomial(r.numerator_exact) << "\n  Q(z) = " << polynomial(r.denominator_exact) << "\n";
    print_stability(check_a_stability(c));
    const BlockCoefficients partner = generate_block_method(step_control_partner(spec));
    std::cout << "the step control's (s+1)-point block (order " << partner.order << "):\n";
    print_stability(check_a_stability(partner));
  } else {
    const ZeroStability z = check_zero_stability(c);
    std::cout << "zero-stability: largest parasitic root " << z.parasitic_radius << ": "
              << (!z.zero_stable ? "not zero-stable" : z.strongly ? "zero-stable" : "weakly zero-stable") << "\n";
  }
  return 0;
}

// The table of docs/methods.md: one-step methods s = 1..6 at maximal and lowest order,
// equidistant and at Radau points.
int stability_table() {
  std::cout << "| points | s | order | R(z) at infinity | max abs R(iy) | A-stable |\n|---|---|---|---|---|---|\n";
  for (int s = 1; s <= 7; ++s) {
    for (int order : {s + 1, s}) {
      const StabilityReport r = check_a_stability(generate_block_method({1, s, order}));
      std::printf("| equidistant | %d | %d%s | %.3g | %.4g | %s |\n", s, order, order == s + 1 ? " (maximal)" : "", r.at_infinity,
                  r.max_on_imaginary_axis, r.a_stable ? "yes" : "no");
    }
    const StabilityReport r = check_a_stability(generate_block_method({1, s, 0, BlockNodes::radau}));
    std::printf("| Radau | %d | %d | %.3g | %.4g | %s |\n", s, 2 * s - 1, r.at_infinity, r.max_on_imaginary_axis,
                r.a_stable ? "yes" : "no");
  }
  std::cout << "\n| m | s | order | parasitic root | zero-stable |\n|---|---|---|---|---|\n";
  for (int m = 2; m <= 4; ++m)
    for (int s = 1; s <= 3; ++s)
      for (int order = m + s; order <= 2 * m + s - 1; ++order) {
        const ZeroStability z = check_zero_stability(generate_block_method({m, s, order}));
        std::printf("| %d | %d | %d%s | %.3g | %s |\n", m, s, order, order == 2 * m + s - 1 ? " (maximal)" : "",
                    z.parasitic_radius, !z.zero_stable ? "no" : z.strongly ? "yes" : "weakly");
      }
  return 0;
}

int run(const OdeArgs& a) {
  if (a.problem.empty()) throw InputError(std::string("ode: --problem is required (") + builtin_problem_names + ")");
  if (a.output_given || !a.output.empty()) check_output_path(a.output, {{}, a.force});
  if (a.method == "tirk") return run_tirk(a);
  OdeProblem p;
  BlockSettings s;
  try {
    p = builtin_problem(a.problem, a.n);
    s.method = spec_of(a);
    s.iteration = block_iteration_from_string(a.iteration.empty() ? "newton" : a.iteration);
    apply_common_options(a, p, s);
  } catch (const InputError& e) {
    throw InputError(std::string("ode: ") + e.what());
  }

  OdeRecorder rec(p, !a.output.empty());
  auto on_block = [&](const AcceptedBlock& b) {
    for (int i = 0; i < b.points; ++i) rec.add(b.t0 + b.method->positions(i) * b.tau, (*b.u)[static_cast<std::size_t>(i)]);
  };
  if (!a.quiet)
    std::cerr << "mbsflow ode: " << p.name << " (N = " << p.size << ") on [" << p.t0 << ", " << p.t_end << "], colloc "
              << describe_block_method(s.method) << " (and s + 1 = " << a.s + 1 << "), tol " << a.tol << ", "
              << to_string(s.iteration) << "\n";
  const auto start = std::chrono::steady_clock::now();
  BlockResult r;
  try {
    r = integrate_block(p, s, on_block);
  } catch (const InputError& e) {
    throw InputError(std::string("ode: ") + e.what());
  } catch (const RunError& e) {
    throw RunError(std::string("ode: ") + e.what() + " (try a smaller --tol, or --iteration newton for a stiff problem)");
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const BlockStats& st = r.stats;
  std::printf("steps %ld (accepted %ld: %ld with s+1 = %d points, %ld with s = %d; rejected %ld, of which %ld by the iteration)\n",
              st.steps, st.accepted, st.taken_s1, a.s + 1, st.taken_s, a.s, st.rejected, st.iteration_failures);
  std::printf("rhs evaluations %ld, iterations %ld, Jacobians %ld, factorizations %ld (%s)\n", st.rhs_evaluations,
              st.iterations, st.jacobians, st.factorizations,
              s.iteration == BlockIteration::newton ? to_string(st.linear_solver) : "none");
  if (p.exact) std::printf("max error %.3e (against the exact solution, all accepted points)\n", rec.max_error());
  report_end_error(p, r.y);
  rec.warn_uncontrolled(s.atol, s.atols);
  std::printf("wall time %.3f s\n", seconds);
  rec.write(a.output, r.steps,
            {{"problem", p.name}, {"method", a.method}, {"iteration", to_string(s.iteration)}},
            {{"n", double(p.size)}, {"s", double(a.s)}, {"m", double(a.m)}, {"order", double(s.method.effective_order())},
             {"tol", a.tol}, {"wall_seconds", seconds}, {"rhs_evaluations", double(st.rhs_evaluations)}},
            a.quiet);
  return 0;
}

}  // namespace

Action add_ode(CLI::App& app) {
  auto a = std::make_shared<OdeArgs>();
  CLI::App* sub = app.add_subcommand(
      "ode", "Integrate an ODE test problem with the collocation block methods (colloc) or triangularised implicit Runge-Kutta methods (tirk)");
  sub->add_option("--problem", a->problem,
                  "hnw (eq. 10, Hairer-Wanner), b1 (eq. 11, DETEST B1), heat (eq. 12, --n equations) or heatN, vdp (Van der Pol, "
                  "mu = 1e3, scaled form on [0, 2]) or vdpMU (e.g. vdp1e6), robertson (kinetics on [0, 1e11], per-component atol), hires, orego, e5, pollu (Test Set for IVP Solvers, published end values)");
  sub->add_option("--n", a->n, "heat: number of equations")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--method", a->method, "colloc (collocation block methods) or tirk (implicit Runge-Kutta iterated through a triangular T)")
      ->check(CLI::IsMember({"colloc", "tirk"}))->capture_default_str();
  sub->add_option("--s", a->s, "colloc: points per block (the controller also runs s+1)")->check(CLI::Range(1, 12))->capture_default_str();
  sub->add_option("--m", a->m, "colloc: steps (1: one-step methods)")->check(CLI::Range(1, 8))->capture_default_str();
  sub->add_option("--order", a->order, "colloc: order of an equidistant s-point method (0: maximal, 2m+s-1)")->check(CLI::NonNegativeNumber);
  sub->add_option("--nodes", a->nodes,
                  "colloc: radau (blocks at the Radau points, L-stable, order 2s-1; the default for one-step methods) or "
                  "equidistant (the classical blocks; the default with --m > 1 or --order)")
      ->check(CLI::IsMember({"radau", "equidistant"}));
  sub->add_option("--tableau", a->tableau,
                  "tirk: radau1..radau12 (Radau IIA, s stages), gauss2, gauss3, lobatto3c, block1..block6 (the one-step collocation "
                  "block methods)")
      ->capture_default_str();
  sub->add_option("--tol", a->tol, "relative (and, without --atol, absolute) tolerance")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--rtol", a->rtols, "relative tolerance: one value, or one per equation (default: --tol)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  sub->add_option("--atol", a->atols,
                  "absolute tolerance: one value, or one per equation (default: --tol, times the problem's absolute scale where it "
                  "has one: robertson 1e-4,1e-10,1e-2)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  sub->add_option("--iteration", a->iteration,
                  "colloc: newton (default) or functional; tirk: newton (default, as Radau5: one real and one complex LU for radau3), newton-triangular (PTIRK, the parallel triangular iteration), newton-diagonal, triangular, "
                  "diagonal or jacobi")
      ->check(CLI::IsMember({"newton", "functional", "jacobi", "triangular", "diagonal", "newton-triangular", "newton-diagonal"}));
  sub->add_option("--iterations", a->iterations, "tirk: exactly this many iterations per step, no convergence test (0: until converged)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--inner", a->inner, "tirk, functional triangular/diagonal: substitutions for a stage's own term per iteration")
      ->check(CLI::Range(1, 50))->capture_default_str();
  sub->add_option("--jacobian", a->jacobian,
                  "auto (the problem's exact Jacobian) or differences (finite differences), as for mbsflow run; exact and fd "
                  "are the older names")
      ->check(CLI::IsMember({"auto", "differences", "exact", "fd"}))->capture_default_str();
  sub->add_option("--linear-solver", a->solver, "auto, dense, banded, klu (SuiteSparse) or sparselu (Eigen)")
      ->check(CLI::IsMember({"auto", "dense", "banded", "klu", "sparselu"}))->capture_default_str();
  sub->add_option("--fixed-step", a->fixed_step, "no step control: this step (colloc: the point spacing of equidistant blocks, the block length at Radau points)")->check(CLI::PositiveNumber);
  sub->add_option("--initial-step", a->initial_step, "first step (default: chosen from the problem)")->check(CLI::PositiveNumber);
  sub->add_option("--threads", a->threads, "threads (0: all cores; 1: sequential, the same numbers)")->check(CLI::NonNegativeNumber);
  sub->add_option("-o,--output", a->output,
                  "HDF5 file for the solution and the step record (replaces only an earlier results file, else --force)")
      ->each([a](const std::string&) { a->output_given = true; });
  sub->add_flag("--force", a->force, "With -o: replace the file there even if it is not an mbsflow results file");
  auto describe_name = std::make_shared<std::string>();
  CLI::Option* describe_opt = sub->add_option("--describe", *describe_name,
                                          "print a method's coefficients and properties and exit: a tableau name, or without one the "
                                          "method of --method/--tableau/--m/--s/--order")
                              ->expected(0, 1);
  sub->add_flag("--stability-table", a->stability_table, "print the stability tables of docs/methods.md and exit");
  sub->add_flag("-q,--quiet", a->quiet, "no progress lines on stderr");
  return [a, describe_opt, describe_name] {
    try {
      if (a->stability_table) return stability_table();
      if (describe_opt->count() > 0) {
        if (!describe_name->empty()) return describe_tableau(*describe_name);
        return a->method == "tirk" ? describe_tableau(a->tableau) : describe(*a);
      }
    } catch (const InputError& e) {
      throw InputError(std::string("ode: ") + e.what());
    }
    return run(*a);
  };
}

}  // namespace mbsflow::cli
