#pragma once
// An initial value problem y' = f(t, y), y(t0) = y0, for the implicit methods: the user
// system of the library API and the built-in test problems.
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace mbsflow {

// Rows [begin, end) of a vector: the right-hand side may be asked for a slice of the
// equations only, so that large systems split their work over threads.
struct RowRange {
  Eigen::Index begin = 0, end = 0;
};

struct OdeProblem {
  std::string name;
  Eigen::Index size = 0;
  double t0 = 0, t_end = 1;
  Eigen::VectorXd y0;
  // dydt[rows] = f(t, y)[rows]; y is the whole state, only the rows in the range are
  // written. A system that cannot split its evaluation computes what it needs for the range.
  std::function<void(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt, RowRange rows)> rhs;
  // Whether asking for a slice of rows costs only that slice (false: the whole vector is
  // computed anyway, so solvers ask for whole vectors).
  bool sliceable = true;
  // Optional: the Jacobian df/dy at (t, y), written into a matrix whose sparsity pattern is
  // `sparsity` (or dense when no pattern is given).
  std::function<void(double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac)> jacobian;
  // Optional: the structural non-zeros of df/dy (values ignored). Without it the Jacobian
  // is taken as dense; with it finite differences need one evaluation per column colour.
  std::optional<Eigen::SparseMatrix<double>> sparsity;
  // Optional: what unknown i is (e.g. "the velocity of body 'link3'"), for failure messages.
  std::function<std::string(Eigen::Index i)> describe;
  // Optional: the exact solution, for error reports and tests.
  std::function<Eigen::VectorXd(double t)> exact;
  // Optional: a published value of y(t_end) (where no exact solution is known), and its source.
  Eigen::VectorXd end_reference;
  std::string end_reference_source;
  // Optional: per component, the magnitude below which it is controlled in absolute terms
  // (atol_i = rtol * absolute_scale_i: chemical kinetics with components of 1e-14 next to
  // ones of 1); empty: 1 for all, i.e. atol = rtol.
  Eigen::VectorXd absolute_scale;
  // Optional: small blocks of unknowns whose rates read, among the unknowns of all blocks,
  // only their own block (a body's position, r' = v, and its quaternion, q' = q (x) (0, w) / 2).
  // The sparse Newton solvers eliminate them first and factorise the rest (the Schur
  // complement, schur_reduction.hpp), where the Jacobian's pattern allows it.
  std::vector<RowRange> eliminable;

  void evaluate(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) const { rhs(t, y, dydt, {0, size}); }
};

// The problem's absolute_scale, or ones where it has none.
inline Eigen::VectorXd absolute_scales(const OdeProblem& p) {
  return p.absolute_scale.size() > 0 ? p.absolute_scale : Eigen::VectorXd::Ones(p.size);
}

// A problem from a whole-vector right-hand side f(t, y, dydt) (no slicing).
template <class F>
OdeProblem make_ode_problem(std::string name, double t0, double t_end, Eigen::VectorXd y0, F f) {
  OdeProblem p;
  p.name = std::move(name);
  p.size = y0.size();
  p.t0 = t0;
  p.t_end = t_end;
  p.y0 = std::move(y0);
  p.sliceable = false;
  // Evaluated whole, once per call, and copied into the requested rows.
  p.rhs = [f = std::move(f)](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt, RowRange rows) {
    if (rows.begin == 0 && rows.end == y.size()) {
      f(t, y, dydt);
      return;
    }
    Eigen::VectorXd all(y.size());
    f(t, y, all);
    dydt.segment(rows.begin, rows.end - rows.begin) = all.segment(rows.begin, rows.end - rows.begin);
  };
  return p;
}

// The seed's test problems (eqs. 10-12 of seed 001), each with its exact solution and
// exact Jacobian.
OdeProblem hairer_wanner_problem();  // eq. 10 on [0, 2.5]
OdeProblem detest_b1_problem();      // eq. 11 on [0, 20]
OdeProblem heat_problem(Eigen::Index n);  // eq. 12 on [0, 4]
// Standard stiff problems of the Test Set for IVP Solvers (Mazzia, Magherini et al.,
// Bari): Van der Pol in Hairer-Wanner's scaled form y1' = y2, y2' = ((1 - y1^2) y2 - y1) / eps
// with eps = 1 / mu^2, y(0) = (2, 0), on [0, 2] (the test set's VDPOL is mu = 1e3, whose
// y(2) is the published reference); Robertson's kinetics on [0, 1e11] (ROBER, with its
// published y(1e11)).
OdeProblem van_der_pol_problem(double mu);
OdeProblem robertson_problem();
// More of the test set, each with its published y(t_end): HIRES (8 equations on [0,
// 321.8122], plant physiology), OREGO (the Oregonator, 3 equations on [0, 360]), E5
// (4 equations of chemical pyrolysis on [0, 1e13], components of 1e-290 to 1e-3) and
// POLLU (air pollution, 25 reactions of 20 species on [0, 60]).
OdeProblem hires_problem();
OdeProblem oregonator_problem();
OdeProblem e5_problem();
OdeProblem pollution_problem();
// By name: "hnw", "b1", "heat" (n equations) or "heatN", "vdp" (mu = 1e3) or "vdpMU"
// ("vdp1e6"), "robertson", "hires", "orego", "e5", "pollu"; throws InputError otherwise.
OdeProblem builtin_problem(const std::string& name, Eigen::Index n);
// The names builtin_problem knows, for help texts.
inline constexpr const char* builtin_problem_names = "hnw, b1, heat, heatN, vdp, vdpMU (e.g. vdp1e6), robertson, hires, orego, e5, pollu";

}  // namespace mbsflow
