// mbsflow bench stiff: work-precision of the implicit methods on stiff multibody models: a
// chain of bushings in the natural-frequency form at several frequencies, the train with
// stiff couplers and the IFToMM A05 flyball governor, each against RK4 at its stable step,
// DOPRI5 and CVODE (BDF + KLU on the same right-hand side and Jacobian: analytic where the
// model has one, else coloured differences).
// Every run writes the body positions every 1 ms of model time; its error is the largest
// distance of a body from a tight-tolerance run of the same model.
#include <oneapi/tbb/info.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>

#include "bench.hpp"
#include "cvode_driver.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/run.hpp"
#include "mbsflow/runtime/run_request.hpp"

namespace mbsflow::cli {
namespace {

constexpr double output_interval = 1e-3;

struct Case {
  std::string name;
  Model model;
};

// A sink for the body positions at every output time.
KeptStates positions() {
  KeptStates k;
  k.positions_only = true;
  return k;
}

// Largest distance of a body from the reference over all output times; infinity when the
// run stopped early or left the grid.
double position_error(const KeptStates& run, const KeptStates& ref) {
  if (run.t.size() != ref.t.size()) return INFINITY;
  double e = 0;
  for (std::size_t k = 0; k < run.t.size(); ++k) {
    if (std::abs(run.t[k] - ref.t[k]) > 1e-9) return INFINITY;
    const Eigen::VectorXd d = run.y[k] - ref.y[k];
    for (Eigen::Index i = 0; i < d.size(); i += 3) e = std::max(e, d.segment<3>(i).norm());
  }
  return std::isfinite(e) ? e : INFINITY;
}

std::vector<Case> stiff_cases(const BenchArgs& a) {
  std::vector<Case> out;
  const std::vector<std::string> problems = a.problems.empty() ? std::vector<std::string>{"chain", "train", "a05"} : a.problems;
  for (const std::string& p : problems) {
    if (p == "chain") {
      ChainParams cp;
      cp.bodies = a.bodies.empty() ? 2000 : a.bodies.front();
      for (double omega : a.frequencies.empty() ? std::vector<double>{1e3, 1e4, 1e5} : a.frequencies) {
        char name[48];
        std::snprintf(name, sizeof name, "chain%d W=%.0e", cp.bodies, omega);
        Case c{name, make_chain(cp)};
        for (Joint& j : c.model.joints) set_bushing_from_frequency(c.model, j, omega, 0.02);
        c.model.simulation.t_end = a.t_end > 0 ? a.t_end : 0.2;
        out.push_back(std::move(c));
      }
    } else if (p == "train") {
      TrainParams tp;
      tp.wagons = 10;
      Case c{"train10 couplers W=1e4", make_train(tp)};
      for (Joint& j : c.model.joints)
        if (j.name.rfind("coupler", 0) == 0) set_bushing_from_frequency(c.model, j, 1e4, 0.02);
      c.model.simulation.t_end = a.t_end > 0 ? a.t_end : 1.0;
      out.push_back(std::move(c));
    } else if (p == "a05") {
      Case c{"A05 flyball governor",
             read_model_file(examples_dir(a) + "/iftomm_a05_flyball_governor.json")};
      if (a.t_end > 0) c.model.simulation.t_end = a.t_end;
      out.push_back(std::move(c));
    } else {
      throw InputError("bench stiff: unknown problem '" + p + "' (chain, train, a05)");
    }
  }
  return out;
}

OdeProblem multibody_problem(MultibodySystem& sys, double t_end) {
  OdeProblem p = make_ode_problem("multibody", 0.0, t_end, sys.initial_state(),
                                  [&sys](double t, const Eigen::VectorXd& y, Eigen::VectorXd& f) { sys.rhs(t, y, f); });
  p.sparsity = sys.jacobian_pattern();
  if (sys.has_analytic_jacobian())
    p.jacobian = [&sys](double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac) { sys.jacobian(t, y, jac); };
  return p;
}

// RK4's stable step: 2.78 / rho(J(0, y0)) (its stability interval on the negative real
// axis, 2.83 on the imaginary one), rho by power iteration on the coloured-difference
// Jacobian, shortened to a whole number of steps per output interval.
double rk4_stable_step(const Model& m) {
  MultibodySystem sys(m);
  const OdeProblem p = multibody_problem(sys, m.simulation.t_end);
  Eigen::VectorXd f(p.size);
  p.evaluate(0.0, p.y0, f);
  long evaluations = 0;
  JacobianEvaluator jac(p, true);
  const Eigen::SparseMatrix<double> j = jac.evaluate(0.0, p.y0, f, evaluations);
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(p.size, 1.0, 2.0), w;
  for (int k = 0; k < 500; ++k) {
    w = j * v;
    v = w / w.norm();
  }
  // Two products: a complex pair of dominant eigenvalues rotates v instead of fixing it.
  const double rho = std::sqrt((j * (j * v)).norm());
  const double h = 2.78 / rho;
  return output_interval / std::ceil(output_interval / h);
}

struct StiffRow {
  std::string method;
  int threads = 1;
  double tol = 0;
  long steps = 0, evaluations = 0, jacobians = 0, factorizations = 0;
  double seconds = 0, error = INFINITY;
  std::string note;
};

// The method column: the method, and the variant after a dash.
std::string row_name(Method method, const std::string& variant) {
  return variant.empty() ? method_name(method) : std::string(method_name(method)) + "-" + variant;
}

// One run of the runtime: implicit methods whole with `threads`, explicit ones cut into
// submodels on `threads` (one submodel on one thread).
StiffRow run_method(const Model& m, Method method, double tol, double step, int threads, KeptStates& out,
               const std::string& variant = "") {
  StiffRow r;
  r.method = row_name(method, variant);
  r.threads = threads;
  r.tol = tol;
  RunPlan plan;
  plan.options = options_from_model(m);
  plan.options.method = method;
  plan.options.variant = variant;
  plan.options.rtol = plan.options.atol = tol;
  if (step > 0) plan.options.step = step;
  plan.options.output_interval = output_interval;
  plan.options.threads = threads;
  plan.parallel.threads = threads;
  const auto start = BenchClock::now();
  try {
    // Cut as `mbsflow run` cuts it with these threads and no --partitions.
    plan.partition = cut_for_run(m, std::nullopt, default_submodels(m, method, false, threads), Partitioner::best, true);
    const RunSummary s = run(m, plan, &out);
    r.steps = s.steps;
    r.evaluations = s.evaluations;
    r.jacobians = s.jacobians;
    r.factorizations = s.factorizations;
  } catch (const RunError& e) {
    r.note = e.what();
  }
  r.seconds = seconds_since(start);
  return r;
}

StiffRow run_cvode_klu(const Model& m, double tol, KeptStates& out) {
  StiffRow r;
  r.method = "cvode-klu";
  r.tol = tol;
  const auto start = BenchClock::now();
  MultibodySystem sys(m);
  const double t_end = m.simulation.t_end;
  const OdeProblem p = multibody_problem(sys, t_end);
  out.begin(sys);
  std::vector<double> times;  // after t = 0, whose snapshot is the initial state
  for (long k = 1; output_interval * k <= t_end * (1 + 1e-12); ++k) times.push_back(output_interval * k);
  Snapshot first;
  first.state = p.y0;
  out.write(std::move(first));
  const CvodeOutcome c = run_cvode(p, tol, tol, CvodeLinearSolver::klu, times,
                                   [&](double t, const double* y) {
                                     Snapshot s;
                                     s.t = t;
                                     s.state = Eigen::Map<const Eigen::VectorXd>(y, p.size);
                                     // As a run's snapshots: unit quaternions, driven bodies exactly on their motion.
                                     sys.after_step(t, s.state);
                                     out.write(std::move(s));
                                   },
                                   {}, [&sys](double t, Eigen::VectorXd& y) { sys.after_step(t, y); });
  r.seconds = seconds_since(start);
  r.steps = c.steps;
  r.evaluations = c.evaluations;
  r.jacobians = c.jacobians;
  r.factorizations = c.setups;
  if (!c.ok) r.note = c.note;
  return r;
}

void print_row(const std::string& name, const StiffRow& r, BenchCsv& csv) {
  std::printf("%-24s %-10s %3d %8.0e %8ld %9ld %6ld %7ld %9.3f %10.3g %s\n", name.c_str(), r.method.c_str(), r.threads, r.tol,
              r.steps, r.evaluations, r.jacobians, r.factorizations, r.seconds, r.error, r.note.c_str());
  std::fflush(stdout);
  csv.out << '"' << name << "\"," << r.method << ',' << r.threads << ',' << r.tol << ',' << r.steps << ',' << r.evaluations << ','
          << r.jacobians << ',' << r.factorizations << ',' << r.seconds << ',' << r.error << ",\"" << r.note << "\"" << std::endl;  // kept if the run is stopped
}

}  // namespace

int bench_stiff(const BenchArgs& a) {
  const std::vector<Case> cases = stiff_cases(a);
  const std::vector<double> tols = a.tolerances.empty() ? std::vector<double>{1e-1, 1e-2, 1e-3, 1e-4} : a.tolerances;
  const int all = a.threads > 0 ? a.threads : tbb::info::default_concurrency();
  const double reference_tol = a.reference_tol > 0 ? a.reference_tol : 1e-6;
  std::vector<int> thread_counts{1};
  if (all > 1) thread_counts.push_back(all);
  BenchCsv csv = open_csv(a);
  csv.out << "model,method,threads,tol,steps,evaluations,jacobians,factorizations,wall_s,error_m,note\n";
  std::printf("error: largest distance of a body from a tirk run at tolerance %.0e, positions every %.0f ms\n",
              reference_tol, output_interval * 1e3);
  std::printf("%-24s %-10s %3s %8s %8s %9s %6s %7s %9s %10s\n", "model", "method", "thr", "tol", "steps", "rhs", "jac", "factor",
              "wall s", "error m");
  struct Best {
    double seconds = INFINITY;
    std::string how;
  };
  std::vector<std::pair<std::string, std::map<std::string, Best>>> summary;
  auto wanted = [&](const std::string& method) {
    return a.methods.empty() || std::find(a.methods.begin(), a.methods.end(), method) != a.methods.end();
  };
  for (const Case& c : cases) {
    KeptStates ref = positions();
    StiffRow rr = run_method(c.model, Method::tirk, reference_tol, 0, all, ref);
    rr.method = "reference";
    rr.error = 0;
    print_row(c.name, rr, csv);
    if (!rr.note.empty()) continue;
    std::map<std::string, Best> best;
    auto record = [&](StiffRow r, const KeptStates& out) {
      if (r.note.empty()) r.error = position_error(out, ref);
      print_row(c.name, r, csv);
      if (r.threads != 1 || !(r.error <= a.target_error)) return;
      Best& b = best[r.method];
      if (r.seconds < b.seconds) {
        char how[64];
        std::snprintf(how, sizeof how, "tol %.0e: %.3g m", r.tol, r.error);
        b = {r.seconds, how};
      }
    };
    if (wanted("rk4")) {
      const double h = rk4_stable_step(c.model);
      for (int threads : thread_counts) {
        KeptStates out = positions();
        StiffRow r = run_method(c.model, Method::rk4, 0, h, threads, out);
        r.tol = h;  // the step, in the tolerance column
        record(r, out);
      }
    }
    // tirk twice: the full Newton iteration (as Radau5) and the seed's triangular one.
    const std::vector<std::pair<Method, std::string>> methods = {
        {Method::dopri5, ""}, {Method::tirk, "newton"}, {Method::tirk, "newton-triangular"}, {Method::colloc, ""}};
    // A method none of whose one-thread runs reached the target error runs again, on one
    // thread, at tolerances ten times tighter than the tightest given, down to 1e-9, until
    // one does: the summary then compares every method that can reach it (CVODE reaches
    // 1e-3 m on A05 only at tol 1e-7).
    const double tightest = *std::min_element(tols.begin(), tols.end());
    auto tighten = [&](const std::string& method, const std::function<void(double)>& run_at) {
      for (double tol = tightest / 10; !best.count(method) && tol >= 1e-9 * (1 - 1e-6); tol /= 10) run_at(tol);
    };
    for (const auto& [m, variant] : methods) {
      if (!wanted(row_name(m, variant))) continue;
      auto run_at = [&, m = m, variant = variant](double tol, int threads) {
        KeptStates out = positions();
        record(run_method(c.model, m, tol, 0, threads, out, variant), out);
      };
      for (double tol : tols)
        for (int threads : thread_counts) run_at(tol, threads);
      tighten(row_name(m, variant), [&](double tol) { run_at(tol, 1); });
    }
    if (wanted("cvode-klu")) {
      auto run_at = [&](double tol) {
        KeptStates out = positions();
        record(run_cvode_klu(c.model, tol, out), out);
      };
      for (double tol : tols) run_at(tol);
      tighten("cvode-klu", run_at);
    }
    summary.emplace_back(c.name, best);
  }
  std::printf("\nfastest run on 1 thread with error <= %.0e m (rk4: at its stable step, tol column = step)\n", a.target_error);
  std::printf("%-24s %-10s %9s %12s %12s   %s\n", "model", "method", "wall s", "rk4 / this", "cvode / this", "run");
  for (const auto& [name, best] : summary)
    for (const auto& [method, b] : best) {
      auto ratio = [&](const char* other) {
        const auto it = best.find(other);
        return it == best.end() ? NAN : it->second.seconds / b.seconds;
      };
      std::printf("%-24s %-10s %9.3f %12.2f %12.2f   %s\n", name.c_str(), method.c_str(), b.seconds, ratio("rk4"),
                  ratio("cvode-klu"), b.how.c_str());
    }
  std::printf("wrote %s\n", csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
