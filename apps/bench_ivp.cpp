// mbsflow bench ivp: work-precision of the implicit methods against SUNDIALS CVODE (BDF,
// Newton with the exact Jacobian, dense or band LU) on standard stiff problems (Van der Pol,
// Robertson) and the seed's (eqs. 10-12): correct digits at the end against CPU time over a
// range of tolerances, and each method's time relative to CVODE's at equal digits.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "bench.hpp"
#include "cvode_driver.hpp"
#include "mbsflow/methods/block_integrator.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

namespace mbsflow::cli {
namespace {

struct IvpRun {
  bool ok = false;
  double seconds = 0, scd = 0;
  long steps = 0, rejected = 0, rhs = 0, jacobians = 0, factorizations = 0;
  std::string note;
};

// The tolerances of one run: rtol, and atol_i = rtol * absolute_scale_i, or atol = ratio *
// rtol for every component (--atol-ratio; 1 is what a user who gives one tolerance gets: on
// Robertson's problem it leaves the 1e-5 component uncontrolled, and a solution that crosses
// zero there can grow without bound while every step meets its tolerance).
struct Tolerance {
  double rtol = 0;
  Eigen::VectorXd atols;
};
Tolerance tolerance_for(const OdeProblem& p, double rtol, double atol_ratio) {
  return {rtol, atol_ratio > 0 ? Eigen::VectorXd::Constant(p.size, atol_ratio * rtol).eval() : (rtol * absolute_scales(p)).eval()};
}

// Significant correct digits at the end, in the mixed sense of the test set: components
// below their absolute scale count in absolute terms.
double correct_digits(const OdeProblem& p, const Eigen::VectorXd& y, const Eigen::VectorXd& reference) {
  const Eigen::VectorXd scale = absolute_scales(p);
  double worst = 0;
  for (Eigen::Index i = 0; i < p.size; ++i)
    worst = std::max(worst, std::abs(y(i) - reference(i)) / (std::abs(reference(i)) + scale(i)));
  return worst > 0 ? -std::log10(worst) : 17.0;
}

// y(t_end) to measure against, and the digits it can measure (17: exact or published).
struct Reference {
  Eigen::VectorXd y;
  double digits = 17;
};

const std::vector<std::string>& all_methods() {
  static const std::vector<std::string> names = {"colloc", "colloc-s2", "tirk-newton", "tirk-newton-triangular", "cvode-bdf"};
  return names;
}

// One integration to t_end; its end value in y. Throws nothing: a failure is a row.
IvpRun integrate_once(const std::string& method, const OdeProblem& p, const Tolerance& tol, int threads, Eigen::VectorXd& y) {
  IvpRun r;
  const auto start = BenchClock::now();
  if (method == "cvode-bdf") {
    const CvodeLinearSolver solver = p.size > 100 ? CvodeLinearSolver::band : CvodeLinearSolver::dense;
    const CvodeOutcome c =
        run_cvode(p, tol.rtol, tol.rtol, solver, {p.t_end}, [&](double, const double* v) { y = Eigen::Map<const Eigen::VectorXd>(v, p.size); },
                  tol.atols);
    r = {c.ok, 0, 0, c.steps, 0, c.evaluations, c.jacobians, c.setups, c.note};
  } else {
    // Both families take the same tolerances and thread count, and report the same counts.
    auto integrate = [&](auto settings, auto run) {
      settings.rtol = tol.rtol;
      settings.atols = tol.atols;
      settings.threads = threads;
      const auto result = run(p, settings);
      y = result.y;
      const auto& st = result.stats;
      r = {true, 0, 0, st.steps, st.rejected, st.rhs_evaluations, st.jacobians, st.factorizations, ""};
    };
    try {
      if (method.rfind("colloc", 0) == 0) {
        BlockSettings s;
        if (method == "colloc-s2") s.method = {1, 2, 0, BlockNodes::radau};
        integrate(s, [](const OdeProblem& q, const BlockSettings& bs) { return integrate_block(q, bs); });
      } else {
        TirkSettings s;
        s.iteration = method == "tirk-newton" ? TirkIteration::newton : TirkIteration::newton_triangular;
        integrate(s, [](const OdeProblem& q, const TirkSettings& ts) { return integrate_tirk(q, ts); });
      }
    } catch (const Error& e) {
      r.ok = false;
      r.note = e.what();
    }
  }
  r.seconds = seconds_since(start);
  if (r.ok && !y.allFinite()) {
    r.ok = false;
    r.note = "not finite at the end";
  }
  return r;
}

// The fastest of repeated runs (short runs are repeated until 0.2 s are spent, at most 10
// times, so that timer noise does not decide a ratio); the counts are those of one run.
IvpRun measure(const std::string& method, const OdeProblem& p, const Tolerance& tol, int threads, const Reference& reference) {
  Eigen::VectorXd y;
  IvpRun best = integrate_once(method, p, tol, threads, y);
  if (!best.ok) return best;
  best.scd = std::min(correct_digits(p, y, reference.y), reference.digits);
  double spent = best.seconds;
  for (int k = 1; k < 10 && spent < 0.2; ++k) {
    const IvpRun again = integrate_once(method, p, tol, threads, y);
    spent += again.seconds;
    best.seconds = std::min(best.seconds, again.seconds);
  }
  return best;
}

// y(t_end) to measure against: the exact solution, a published value, or else the run of
// colloc at reference_tol, checked against tirk-newton at the same tolerance; their
// agreement bounds the digits that can be measured (digits above it are cut to it).
Reference reference_of(const OdeProblem& p, double reference_tol) {  // always at the problem's own scales
  if (p.exact) {
    std::printf("%s: exact solution\n", p.name.c_str());
    return {p.exact(p.t_end)};
  }
  if (p.end_reference.size() == p.size) {
    std::printf("%s: reference %s\n", p.name.c_str(), p.end_reference_source.c_str());
    return {p.end_reference};
  }
  // A reference tolerance at which either method stops with a step size underflow (Van der
  // Pol with mu = 1e6 changes by 3 within 1e-12 around t = 0.8, where steps cannot go below
  // 10 eps |t|) is loosened tenfold until both succeed, and the printed line says so.
  Eigen::VectorXd colloc, tirk;
  for (double rtol = reference_tol;; rtol *= 10) {
    const Tolerance tol = tolerance_for(p, rtol, 0);
    const IvpRun a = integrate_once("colloc", p, tol, 0, colloc), b = integrate_once("tirk-newton", p, tol, 0, tirk);
    if (!a.ok || !b.ok) {
      const std::string why = (a.ok ? "tirk-newton: " + b.note : "colloc: " + a.note);
      if (rtol >= 1e-8) throw RunError("bench ivp: the reference runs at rtol " + std::to_string(rtol) + " failed (" + why + ")");
      std::printf("%s: no reference at rtol %.0e (%s), trying %.0e\n", p.name.c_str(), rtol, why.c_str(), rtol * 10);
      continue;
    }
    const double agreement = correct_digits(p, tirk, colloc);
    std::printf("%s: reference computed by colloc at rtol %.0e (%.1f s); tirk-newton at the same rtol agrees to %.1f digits, "
                "so digits above %.1f are not measured\n",
                p.name.c_str(), rtol, a.seconds, agreement, agreement);
    return {colloc, agreement};
  }
}

// A solver's work-precision front: (digits, log seconds) of its runs that no faster run of
// the same solver matches in digits, by digits. A run at a tighter tolerance that reaches no
// more digits than a faster one (E5's floor of double precision, about 5 digits for every
// solver) is not a point of it: a user who wants those digits takes the faster run.
std::vector<std::pair<double, double>> front_of(const std::vector<IvpRun>& runs) {
  std::vector<const IvpRun*> by_time;
  for (const IvpRun& r : runs)
    if (r.ok) by_time.push_back(&r);
  std::sort(by_time.begin(), by_time.end(), [](const IvpRun* a, const IvpRun* b) { return a->seconds < b->seconds; });
  std::vector<std::pair<double, double>> front;
  for (const IvpRun* r : by_time)
    if (front.empty() || r->scd > front.back().first) front.emplace_back(r->scd, std::log(r->seconds));
  return front;
}

// The time to `digits` correct digits on a front, interpolated log-linearly between its
// points; NaN outside the digits it reached.
double seconds_at(const std::vector<std::pair<double, double>>& front, double digits) {
  for (std::size_t k = 0; k + 1 < front.size(); ++k) {
    const auto [d0, l0] = front[k];
    const auto [d1, l1] = front[k + 1];
    if (digits >= d0 && digits <= d1) return std::exp(l0 + (l1 - l0) * (digits - d0) / (d1 - d0));
  }
  return front.size() == 1 && digits == front[0].first ? std::exp(front[0].second) : NAN;
}

}  // namespace

int bench_ivp(const BenchArgs& a) {
  const std::vector<std::string> problems =
      a.problems.empty() ? std::vector<std::string>{"vdp1e3", "vdp1e6", "robertson", "hires", "orego", "e5", "pollu", "hnw", "b1", "heat1000"} : a.problems;
  std::vector<double> tols = a.tolerances;
  if (tols.empty())
    for (int k = 3; k <= 10; ++k) tols.push_back(std::pow(10.0, -k));
  const std::vector<std::string> methods = a.methods.empty() ? all_methods() : a.methods;
  const double reference_tol = a.reference_tol > 0 ? a.reference_tol : 1e-12;
  BenchCsv csv = open_csv(a);
  if (a.atol_ratio > 0) std::printf("atol = %g rtol for every component (--atol-ratio)\n", a.atol_ratio);
  csv.out << "problem,n,solver,threads,rtol,ok,seconds,scd,steps,rejected,rhs_evaluations,jacobians,factorizations,note\n";
  struct Key {
    std::string problem, method;
    int threads;
    bool operator<(const Key& o) const { return std::tie(problem, method, threads) < std::tie(o.problem, o.method, o.threads); }
  };
  std::map<Key, std::vector<IvpRun>> runs;
  for (const std::string& name : problems) {
    const OdeProblem p = builtin_problem(name, 4);
    const Reference reference = reference_of(p, reference_tol);
    std::printf("%-10s %6s %-24s %3s %7s %9s %6s %8s %6s %9s %6s %6s\n", "problem", "N", "solver", "thr", "rtol", "seconds", "scd",
                "steps", "rej", "f evals", "jacs", "LUs");
    for (const std::string& method : methods) {
      std::vector<int> thread_counts = {1};
      // Thread counts only pay where there are equations to split (the stage and point
      // solves of a 2-4 equation system are too small to hand to other cores).
      if (method != "cvode-bdf" && p.size >= 100) thread_counts.push_back(a.threads > 1 ? a.threads : 2);
      // CVODE also runs two decades below the tightest tolerance: the implicit Runge-Kutta
      // methods reach more digits than asked, and its curve must cover theirs to be compared.
      std::vector<double> rtols = tols;
      if (method == "cvode-bdf") {
        const double tightest = *std::min_element(tols.begin(), tols.end());
        for (double extra : {tightest / 10, tightest / 100})
          if (extra >= 1e-13) rtols.push_back(extra);
      }
      for (int threads : thread_counts)
        for (double rtol : rtols) {
          const IvpRun r = measure(method, p, tolerance_for(p, rtol, a.atol_ratio), threads, reference);
          runs[{p.name, method, threads}].push_back(r);
          std::printf("%-10s %6ld %-24s %3d %7.0e %9.4f %6.2f %8ld %6ld %9ld %6ld %6ld %s\n", name.c_str(), long(p.size), method.c_str(),
                      threads, rtol, r.seconds, r.scd, r.steps, r.rejected, r.rhs, r.jacobians, r.factorizations,
                      r.ok ? "" : ("FAILED: " + r.note).c_str());
          csv.out << name << ',' << p.size << ',' << method << ',' << threads << ',' << rtol << ',' << (r.ok ? 1 : 0) << ',' << r.seconds
                  << ',' << r.scd << ',' << r.steps << ',' << r.rejected << ',' << r.rhs << ',' << r.jacobians << ','
                  << r.factorizations << ",\"" << r.note << "\"\n";
          std::fflush(stdout);
        }
    }
  }
  // Matched-accuracy time relative to CVODE: at the digits of each point of a method's
  // front, its time over CVODE's time on CVODE's front (points outside CVODE's range of
  // digits are not compared). "wrong": runs that ended without an error but with less than
  // one correct digit (a silent wrong answer), CVODE's included.
  std::printf("\ntime / CVODE's time at equal correct digits (median, best and worst over the points of the method's work-precision\n"
              "front inside CVODE's range of digits: runs that no faster run of the same solver matches in digits);\n"
              "wrong: runs that ended without an error but with less than one correct digit\n");
  std::printf("%-10s %-24s %3s %8s %6s %9s %8s %8s %8s\n", "problem", "method", "thr", "ok", "wrong", "compared", "median", "best",
              "worst");
  for (const auto& [key, list] : runs) {
    const auto cvode = runs.find({key.problem, "cvode-bdf", 1});
    std::vector<double> ratios;
    long ok = 0, wrong = 0;
    for (const IvpRun& r : list) {
      ok += r.ok;
      wrong += r.ok && r.scd < 1.0;
    }
    if (key.method != "cvode-bdf" && cvode != runs.end()) {
      const auto reference = front_of(cvode->second);
      for (const auto& [digits, log_seconds] : front_of(list))
        if (const double c = seconds_at(reference, digits); std::isfinite(c)) ratios.push_back(std::exp(log_seconds) / c);
    }
    std::sort(ratios.begin(), ratios.end());
    const std::string counted = std::to_string(ok) + "/" + std::to_string(list.size());
    if (ratios.empty()) {
      std::printf("%-10s %-24s %3d %8s %6ld %9d %8s %8s %8s\n", key.problem.c_str(), key.method.c_str(), key.threads, counted.c_str(),
                  wrong, 0, "-", "-", "-");
    } else {
      std::printf("%-10s %-24s %3d %8s %6ld %9zu %8.2f %8.2f %8.2f\n", key.problem.c_str(), key.method.c_str(), key.threads,
                  counted.c_str(), wrong, ratios.size(), ratios[ratios.size() / 2], ratios.front(), ratios.back());
    }
  }
  std::printf("CSV: %s (work-precision plot: /usr/bin/python3 scripts/plot_work_precision.py %s)\n", csv.path.c_str(), csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
