// The standard stiff problems (Van der Pol, Robertson, HIRES, OREGO, E5, POLLU): their Jacobians
// are df/dy, both implicit methods land within 10 tolerances of the Test Set's published
// end values (E5: within its double-precision floor), Robertson's conservation law holds,
// and an initial layer thinner than 1e-14 at t = 0 (Van der Pol with mu = 1e6) is
// integrated, not refused as a step size underflow.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "mbsflow/methods/block_integrator.hpp"
#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"
#include "methods/error_in_tolerances.hpp"

using namespace mbsflow;

namespace {

// atol_i = rtol * absolute_scale_i, as bench ivp and `mbsflow ode` set them.
Eigen::VectorXd atols_for(const OdeProblem& p, double rtol) {
  return rtol * absolute_scales(p);
}

template <class Settings>
Settings settings_for(const OdeProblem& p, double rtol) {
  Settings s;
  s.rtol = rtol;
  s.atols = atols_for(p, rtol);
  s.threads = 1;
  return s;
}

// The end error in units of the tolerance against the published value.
double end_error_in_tolerances(const OdeProblem& p, const Eigen::VectorXd& y, double rtol) {
  return test::error_in_tolerances(y, p.end_reference, rtol, atols_for(p, rtol).array());
}

}  // namespace

namespace {

// The exact Jacobian at y against central differences with a step of 1e-4 of each
// component: these right-hand sides are at most quadratic in each unknown, so the central
// difference is exact up to rounding, and every entry is checked against its own size
// (E5's run from 1e-10 to 1e13) and a 1e-9 share of its row's largest (rounding of the
// difference quotient).
void check_jacobian(const OdeProblem& p, const Eigen::VectorXd& y) {
  Eigen::VectorXd f(p.size), plus(p.size), minus(p.size);
  p.evaluate(0.0, y, f);
  long evaluations = 0;
  JacobianEvaluator exact(p, false);
  const Eigen::MatrixXd je = Eigen::MatrixXd(exact.evaluate(0.0, y, f, evaluations));
  Eigen::MatrixXd jc(p.size, p.size);
  for (Eigen::Index c = 0; c < p.size; ++c) {
    const double h = 1e-4 * std::abs(y(c));
    Eigen::VectorXd moved = y;
    moved(c) = y(c) + h;
    p.evaluate(0.0, moved, plus);
    moved(c) = y(c) - h;
    p.evaluate(0.0, moved, minus);
    jc.col(c) = (plus - minus) / (2 * h);
  }
  INFO(p.name << "\nexact\n" << je << "\ncentral differences\n" << jc);
  CHECK(!exact.uses_differences());
  for (Eigen::Index r = 0; r < p.size; ++r)
    for (Eigen::Index c = 0; c < p.size; ++c)
      CHECK(std::abs(je(r, c) - jc(r, c)) <= 1e-6 * std::abs(je(r, c)) + 1e-9 * je.row(r).cwiseAbs().maxCoeff());
}

}  // namespace

TEST_CASE("stiff problems: analytic Jacobians agree with finite differences", "[methods][problems]") {
  for (const OdeProblem& p : {builtin_problem("vdp", 0), builtin_problem("vdp1e6", 0), robertson_problem()}) {
    // A state off the initial value, where every entry of J is non-zero.
    Eigen::VectorXd y = p.y0;
    if (p.size == 2) y << 1.3, -0.7;
    else y << 0.9, 3e-5, 0.1;
    check_jacobian(p, y);
  }
  for (const OdeProblem& p : {hires_problem(), oregonator_problem(), e5_problem(), pollution_problem()}) {
    // The test set's: each component near its own size in the run.
    const double size = p.name == "e5" ? 1e-14 : p.name == "orego" ? 10.0 : 0.01;
    Eigen::VectorXd y(p.size);
    for (Eigen::Index i = 0; i < p.size; ++i) y(i) = (p.name == "e5" && i == 0 ? 1e-3 : size) * (1 + 0.1 * double(i));
    check_jacobian(p, y);
  }
}

TEST_CASE("stiff problems: names with parameters, and clear errors", "[methods][problems]") {
  CHECK(builtin_problem("heat50", 0).size == 50);
  CHECK(builtin_problem("vdp1e6", 0).name == "vdp1e6");
  CHECK(builtin_problem("vdp", 0).end_reference.size() == 2);  // mu = 1e3: the Test Set's VDPOL
  CHECK(builtin_problem("vdp1e6", 0).end_reference.size() == 0);
  CHECK_THROWS_WITH(builtin_problem("vdpx", 0), Catch::Contains("not a positive number"));
  CHECK_THROWS_WITH(builtin_problem("heat-3", 0), Catch::Contains("not a positive number"));
  CHECK_THROWS_WITH(builtin_problem("nope", 0), Catch::Contains("robertson, hires, orego, e5, pollu"));
  for (const char* name : {"hires", "orego", "e5", "pollu"}) CHECK(builtin_problem(name, 0).end_reference.size() == builtin_problem(name, 0).size);
}

TEST_CASE("stiff problems: end values within 10 tolerances of the published ones, rtol 1e-4 .. 1e-8", "[methods][problems]") {
  for (const OdeProblem& p : {builtin_problem("vdp", 0), robertson_problem(), hires_problem(), oregonator_problem(), e5_problem(),
                              pollution_problem()}) {
    for (int k = 4; k <= 8; ++k) {
      const double rtol = std::pow(10.0, -k);
      // E5's y2 and y3 (9e-23 at the end) come out to about 1e-25 in double precision
      // whatever the tolerance, CVODE's too (bench ivp: 4.4-5.6 digits at rtol 1e-7 .. 1e-12);
      // below rtol 1e-5 that floor is more than 10 of its tolerances (atol = 1e-20 rtol).
      if (p.name == "e5" && k > 5) {
        const TirkResult t = integrate_tirk(p, settings_for<TirkSettings>(p, rtol));
        const BlockResult c = integrate_block(p, settings_for<BlockSettings>(p, rtol));
        INFO("e5 at rtol " << rtol << ": tirk " << (t.y - p.end_reference).transpose() << ", colloc "
                           << (c.y - p.end_reference).transpose());
        CHECK((t.y - p.end_reference).cwiseAbs().maxCoeff() <= 1e-24);
        CHECK((c.y - p.end_reference).cwiseAbs().maxCoeff() <= 1e-24);
        continue;
      }
      const TirkResult t = integrate_tirk(p, settings_for<TirkSettings>(p, rtol));
      const BlockResult c = integrate_block(p, settings_for<BlockSettings>(p, rtol));
      INFO(p.name << " at rtol " << rtol << ": tirk " << end_error_in_tolerances(p, t.y, rtol) << ", colloc "
                  << end_error_in_tolerances(p, c.y, rtol) << " tolerances");
      CHECK(t.t == p.t_end);
      CHECK(c.t == p.t_end);
      CHECK(end_error_in_tolerances(p, t.y, rtol) <= 10);
      CHECK(end_error_in_tolerances(p, c.y, rtol) <= 10);
      if (p.name == "robertson") {
        // y1 + y2 + y3 = 1: every Newton correction solves with I - h gamma J, whose column
        // sums are those of I (J's columns sum to zero), so only rounding moves the sum.
        CHECK(std::abs(t.y.sum() - 1) < 1e-13);
        CHECK(std::abs(c.y.sum() - 1) < 1e-13);
      }
    }
  }
}

TEST_CASE("stiff problems: Van der Pol with mu = 1e6 through its initial layer and both jumps", "[methods][problems]") {
  // The layer at t = 0 is about 3e-13 thick; at rtol 1e-9 it takes steps below 1e-14, which a
  // floor of 1e-14 refused; both methods must agree on y(2).
  const OdeProblem p = builtin_problem("vdp1e6", 0);
  const TirkResult t = integrate_tirk(p, settings_for<TirkSettings>(p, 1e-9));
  const BlockResult c = integrate_block(p, settings_for<BlockSettings>(p, 1e-9));
  INFO("tirk " << t.y.transpose() << ", colloc " << c.y.transpose());
  CHECK(t.t == p.t_end);
  CHECK(c.t == p.t_end);
  CHECK((t.y - c.y).cwiseAbs().maxCoeff() <= 1e-7 * c.y.cwiseAbs().maxCoeff());
}

TEST_CASE("tirk: the Newton iteration stops at RADAU5's test where Jacobians are cheap, 0.03 where they are dear", "[methods][problems]") {
  const double eps = std::numeric_limits<double>::epsilon();
  CHECK(newton_tolerance(1e-2, true) == 0.03);
  CHECK(newton_tolerance(1e-6, true) == std::sqrt(1e-6));
  CHECK(newton_tolerance(1e-13, true) == 10 * eps / 1e-13);
  CHECK(newton_tolerance(1e-6, false) == 0.03);
  CHECK(newton_tolerance(1e-15, false) == 10 * eps / 1e-15);
  // Robertson (3 equations, a Jacobian costs three f evaluations) at rtol 1e-8: with the
  // iteration stopped at 0.03 of the tolerance its error stayed the end's largest share,
  // 0.035 tolerances (9.5 correct digits); carried to sqrt(rtol) = 1e-4 it ends below
  // 1e-3 of them (11.9 digits), in fewer f evaluations (12610 against 13825).
  const OdeProblem p = robertson_problem();
  const TirkResult t = integrate_tirk(p, settings_for<TirkSettings>(p, 1e-8));
  INFO("end error " << end_error_in_tolerances(p, t.y, 1e-8) << " tolerances, " << t.stats.rhs_evaluations << " f evaluations");
  CHECK(end_error_in_tolerances(p, t.y, 1e-8) < 1e-2);
  // A large system keeps 0.03 and one Jacobian as long as it serves: heat (linear, its
  // Jacobian exact for good) with 2000 equations takes the one it starts with, where the
  // renewal rule of the small systems took 11.
  const OdeProblem heat = builtin_problem("heat", 2000);
  const TirkResult h = integrate_tirk(heat, settings_for<TirkSettings>(heat, 1e-6));
  CHECK(h.t == heat.t_end);
  CHECK(h.stats.jacobians == 1);
}
