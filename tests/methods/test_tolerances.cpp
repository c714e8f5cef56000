// Tolerances as a user of Radau5 or CVODE means them: the error at the end stays within a
// small factor of the tolerance over rtol 1e-3 .. 1e-10 (tolerance proportionality), on a
// non-stiff and a stiff problem with known solutions; per-component absolute tolerances
// control a component far below the others. (Not eq. 10, hnw: its solution amplifies
// local errors by two to three orders of magnitude late in the interval, so no local error
// control keeps its global error within 10 tolerances: in `mbsflow ode --problem hnw --tol
// 1e-6 -o F` the end-point error grew from 0.06 tolerances at t = 1.44 to 12 at 2.47, every
// step's estimate below 1.)
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <vector>

#include "mbsflow/methods/block_integrator.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

#include "methods/error_in_tolerances.hpp"

using namespace mbsflow;
using test::error_in_tolerances;

namespace {

// Prothero-Robinson: y' = lambda (y - sin t) + cos t, y(0) = 0, exact y = sin t; stiff for
// lambda = -1e6 (the stiff component must be damped, not merely stable).
OdeProblem prothero_robinson(double lambda) {
  OdeProblem p = make_ode_problem("prothero-robinson", 0.0, 10.0, Eigen::VectorXd::Zero(1),
                                  [lambda](double t, const Eigen::VectorXd& y, Eigen::VectorXd& f) {
                                    f(0) = lambda * (y(0) - std::sin(t)) + std::cos(t);
                                  });
  p.jacobian = [lambda](double, const Eigen::VectorXd&, Eigen::SparseMatrix<double>& j) {
    j.resize(1, 1);
    j.coeffRef(0, 0) = lambda;
  };
  p.exact = [](double t) { return Eigen::VectorXd::Constant(1, std::sin(t)); };
  return p;
}

struct Solver {
  const char* name;
  std::function<std::pair<double, Eigen::VectorXd>(const OdeProblem&, double rtol, const Eigen::VectorXd& atols)> run;
};

// One run at rtol with per-component atols, 1 thread: (end time, end state).
template <class Settings, class Integrate>
std::pair<double, Eigen::VectorXd> run_with(Integrate integrate, const OdeProblem& p, double rtol, const Eigen::VectorXd& atols) {
  Settings s;
  s.rtol = rtol;
  s.atols = atols;
  s.threads = 1;
  const auto r = integrate(p, s);
  return {r.t, r.y};
}

std::vector<Solver> solvers() {
  auto tirk = [](const OdeProblem& p, const TirkSettings& s) { return integrate_tirk(p, s); };
  auto colloc = [](const OdeProblem& p, const BlockSettings& s) { return integrate_block(p, s); };
  return {{"tirk (radau3, newton)",
           [=](const OdeProblem& p, double rtol, const Eigen::VectorXd& a) { return run_with<TirkSettings>(tirk, p, rtol, a); }},
          {"colloc (Radau points, s = 3)",
           [=](const OdeProblem& p, double rtol, const Eigen::VectorXd& a) { return run_with<BlockSettings>(colloc, p, rtol, a); }}};
}

}  // namespace

TEST_CASE("tolerances: the end error stays within 10 tolerances over rtol 1e-3 .. 1e-10", "[methods][tolerances]") {
  for (const OdeProblem& p : {builtin_problem("b1", 0), builtin_problem("heat", 200), prothero_robinson(-1e6)}) {
    for (const Solver& solver : solvers()) {
      for (int k = 3; k <= 10; ++k) {
        const double rtol = std::pow(10.0, -k);
        const Eigen::VectorXd atols = Eigen::VectorXd::Constant(p.size, rtol);
        const auto [t, y] = solver.run(p, rtol, atols);
        const double err = error_in_tolerances(y, p.exact(t), rtol, atols.array());
        INFO(p.name << ", " << solver.name << ", rtol " << rtol << ": end error " << err << " tolerances");
        CHECK(t == p.t_end);
        CHECK(err <= 10);
      }
    }
  }
}

TEST_CASE("tolerances: a per-component atol controls a component far below the others", "[methods][tolerances]") {
  // y1 ~ 1 and y2 ~ 1e-10 decay at different rates; with one atol of 1e-6 the small one is
  // below every tolerance and goes uncontrolled, with its own atol of 1e-20 it is kept to
  // the relative tolerance.
  OdeProblem p = make_ode_problem("two scales", 0.0, 1.0, Eigen::Vector2d(1.0, 1e-10),
                                  [](double, const Eigen::VectorXd& y, Eigen::VectorXd& f) {
                                    f(0) = -y(0);
                                    f(1) = -10 * y(1) + 1e-10 * std::pow(y(0), 2);
                                  });
  // y2' = -10 y2 + 1e-10 e^{-2t}: y2 = 1e-10 (e^{-2t} / 8 + 7/8 e^{-10t}).
  p.exact = [](double t) { return Eigen::Vector2d(std::exp(-t), 1e-10 * (std::exp(-2 * t) / 8 + 7.0 / 8 * std::exp(-10 * t))); };
  const double rtol = 1e-6;
  for (const Solver& solver : solvers()) {
    auto relative = [&](const Eigen::VectorXd& atols) {
      const auto [t, y] = solver.run(p, rtol, atols);
      return std::abs(y(1) - p.exact(t)(1)) / std::abs(p.exact(t)(1));
    };
    const double own = relative(Eigen::Vector2d(1e-6, 1e-20)), shared = relative(Eigen::Vector2d(1e-6, 1e-6));
    INFO(solver.name << ": relative error of the small component " << own << " with its own atol, " << shared << " without");
    CHECK(own <= 10 * rtol);
    CHECK(shared > 100 * own);  // what the per-component atol bought
  }
  TirkSettings bad;
  bad.atols = Eigen::VectorXd::Constant(3, 1e-6);  // 3 values for 2 equations
  CHECK_THROWS_AS(integrate_tirk(p, bad), InputError);
  bad.atols = Eigen::Vector2d(1e-6, -1);
  CHECK_THROWS_AS(integrate_tirk(p, bad), InputError);
}
