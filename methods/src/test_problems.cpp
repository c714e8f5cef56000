// The test problems of seed 001 (eqs. 10-12), with exact solutions and Jacobians, and two
// standard stiff problems with published reference values.
#include "mbsflow/error.hpp"
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {
namespace {

Eigen::SparseMatrix<double> from_triplets(Eigen::Index n, const std::vector<Eigen::Triplet<double>>& t) {
  Eigen::SparseMatrix<double> m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  m.makeCompressed();
  return m;
}

}  // namespace

OdeProblem hairer_wanner_problem() {
  OdeProblem p;
  p.name = "hnw";
  p.size = 4;
  p.t0 = 0;
  p.t_end = 2.5;
  p.y0 = Eigen::VectorXd::Ones(4);
  p.rhs = [](double t, const Eigen::VectorXd& x, Eigen::VectorXd& dx, RowRange rows) {
    for (Eigen::Index i = rows.begin; i < rows.end; ++i) {
      switch (i) {
        case 0: dx(0) = 2 * t * std::pow(x(1), 0.2) * x(3); break;
        case 1: dx(1) = 10 * t * std::exp(5 * (x(2) - 1)) * x(3); break;
        case 2: dx(2) = 2 * t * x(3); break;
        default: dx(3) = -2 * t * std::log(x(0)); break;
      }
    }
  };
  const std::vector<Eigen::Triplet<double>> pattern = {{0, 1, 1}, {0, 3, 1}, {1, 2, 1}, {1, 3, 1}, {2, 3, 1}, {3, 0, 1}};
  p.sparsity = from_triplets(4, pattern);
  p.jacobian = [](double t, const Eigen::VectorXd& x, Eigen::SparseMatrix<double>& j) {
    const double e = std::exp(5 * (x(2) - 1));
    j = from_triplets(4, {{0, 1, 2 * t * 0.2 * std::pow(x(1), -0.8) * x(3)},
                          {0, 3, 2 * t * std::pow(x(1), 0.2)},
                          {1, 2, 50 * t * e * x(3)},
                          {1, 3, 10 * t * e},
                          {2, 3, 2 * t},
                          {3, 0, -2 * t / x(0)}});
  };
  p.exact = [](double t) {
    const double s = std::sin(t * t);
    Eigen::VectorXd x(4);
    x << std::exp(s), std::exp(5 * s), s + 1, std::cos(t * t);
    return x;
  };
  return p;
}

OdeProblem detest_b1_problem() {
  OdeProblem p;
  p.name = "b1";
  p.size = 4;
  p.t0 = 0;
  p.t_end = 20;
  p.y0 = Eigen::VectorXd(4);
  p.y0 << 1, 0, 1, 0;
  p.rhs = [](double, const Eigen::VectorXd& x, Eigen::VectorXd& dx, RowRange rows) {
    for (Eigen::Index i = rows.begin; i < rows.end; ++i) {
      switch (i) {
        case 0: dx(0) = -x(0) + x(1); break;
        case 1: dx(1) = -100 * x(0) - x(1); break;
        case 2: dx(2) = -100 * x(2) + x(3); break;
        default: dx(3) = -1e4 * x(2) - 100 * x(3); break;
      }
    }
  };
  const std::vector<Eigen::Triplet<double>> a = {{0, 0, -1}, {0, 1, 1},     {1, 0, -100}, {1, 1, -1},
                                                 {2, 2, -100}, {2, 3, 1}, {3, 2, -1e4}, {3, 3, -100}};
  p.sparsity = from_triplets(4, a);
  p.jacobian = [a](double, const Eigen::VectorXd&, Eigen::SparseMatrix<double>& j) { j = from_triplets(4, a); };
  // exp(A t) x(0) in closed form: A is two 2x2 blocks [[a, 1], [-b^2, a]], whose
  // exponential is e^{a t} [[cos bt, sin(bt)/b], [-b sin bt, cos bt]].
  p.exact = [](double t) {
    Eigen::VectorXd x(4);
    x << std::exp(-t) * std::cos(10 * t), -10 * std::exp(-t) * std::sin(10 * t), std::exp(-100 * t) * std::cos(100 * t),
        -100 * std::exp(-100 * t) * std::sin(100 * t);
    return x;
  };
  return p;
}

OdeProblem heat_problem(Eigen::Index n) {
  if (n < 1) throw InputError("heat: N must be at least 1");
  OdeProblem p;
  p.name = "heat";
  p.size = n;
  p.t0 = 0;
  p.t_end = 4;
  const double h2 = double(n + 1) * double(n + 1), w = std::numbers::pi / double(n + 1);
  const double lambda1 = 2 * h2 * (1 - std::cos(w)), lambda2 = 2 * h2 * (1 - std::cos(2 * w));
  // sin(k i pi/(N+1)) for k = 1, 2, computed once: the forcing needs them every evaluation.
  auto s1 = std::make_shared<Eigen::VectorXd>(n), s2 = std::make_shared<Eigen::VectorXd>(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    (*s1)(i) = std::sin(double(i + 1) * w);
    (*s2)(i) = std::sin(2 * double(i + 1) * w);
  }
  p.y0 = *s1 + *s2;
  p.rhs = [=](double t, const Eigen::VectorXd& x, Eigen::VectorXd& dx, RowRange rows) {
    const double f1 = (lambda1 - 1) * std::exp(-t), f2 = (lambda2 - 2) * std::exp(-2 * t);
    for (Eigen::Index i = rows.begin; i < rows.end; ++i) {
      const double left = i > 0 ? x(i - 1) : 0.0, right = i + 1 < n ? x(i + 1) : 0.0;
      dx(i) = h2 * (left - 2 * x(i) + right) + f1 * (*s1)(i) + f2 * (*s2)(i);
    }
  };
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (i > 0) t.emplace_back(i, i - 1, h2);
    t.emplace_back(i, i, -2 * h2);
    if (i + 1 < n) t.emplace_back(i, i + 1, h2);
  }
  auto jac = std::make_shared<Eigen::SparseMatrix<double>>(from_triplets(n, t));
  p.sparsity = *jac;
  p.jacobian = [jac](double, const Eigen::VectorXd&, Eigen::SparseMatrix<double>& j) { j = *jac; };
  p.exact = [=](double tt) -> Eigen::VectorXd { return std::exp(-tt) * *s1 + std::exp(-2 * tt) * *s2; };
  return p;
}

OdeProblem van_der_pol_problem(double mu) {
  if (!(mu > 0)) throw InputError("vdp: mu must be positive");
  const double eps = 1 / (mu * mu);
  Eigen::VectorXd y0(2);
  y0 << 2, 0;
  OdeProblem p = make_ode_problem("vdp", 0, 2, y0, [eps](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    dy(0) = y(1);
    dy(1) = ((1 - y(0) * y(0)) * y(1) - y(0)) / eps;
  });
  p.sparsity = from_triplets(2, {{0, 1, 1}, {1, 0, 1}, {1, 1, 1}});
  p.jacobian = [eps](double, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& j) {
    j = from_triplets(2, {{0, 1, 1}, {1, 0, (-2 * y(0) * y(1) - 1) / eps}, {1, 1, (1 - y(0) * y(0)) / eps}});
  };
  if (mu == 1e3) {
    p.end_reference = Eigen::Vector2d(0.1706167732170483e1, -0.8928097010247975e0);
    p.end_reference_source = "Test Set for IVP Solvers, problem VDPOL (RADAU in extended precision, rtol = atol = 1.1e-18)";
  }
  return p;
}

OdeProblem robertson_problem() {
  OdeProblem p = make_ode_problem("robertson", 0, 1e11, Eigen::Vector3d(1, 0, 0), [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    const double slow = 0.04 * y(0), back = 1e4 * y(1) * y(2), fast = 3e7 * y(1) * y(1);
    dy(0) = -slow + back;
    dy(1) = slow - back - fast;
    dy(2) = fast;
  });
  p.sparsity = from_triplets(3, {{0, 0, 1}, {0, 1, 1}, {0, 2, 1}, {1, 0, 1}, {1, 1, 1}, {1, 2, 1}, {2, 1, 1}});
  p.jacobian = [](double, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& j) {
    j = from_triplets(3, {{0, 0, -0.04},
                          {0, 1, 1e4 * y(2)},
                          {0, 2, 1e4 * y(1)},
                          {1, 0, 0.04},
                          {1, 1, -1e4 * y(2) - 6e7 * y(1)},
                          {1, 2, -1e4 * y(1)},
                          {2, 1, 6e7 * y(1)}});
  };
  // y2 stays below 4e-5 and ends near 1e-13: controlled in absolute terms below 1e-10 of
  // the relative tolerance's scale (SUNDIALS' cvRoberts example: atol = (1e-8, 1e-14, 1e-6) at rtol 1e-4).
  p.absolute_scale = Eigen::Vector3d(1e-4, 1e-10, 1e-2);
  p.end_reference = Eigen::Vector3d(0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050e+00);
  p.end_reference_source = "Test Set for IVP Solvers, problem ROBER";
  return p;
}

OdeProblem builtin_problem(const std::string& name, Eigen::Index n) {
  // A number after the name: "heat1000" (equations), "vdp1e6" (mu).
  auto suffix = [&](const std::string& stem) -> std::optional<std::string> {
    if (name.rfind(stem, 0) != 0 || name.size() == stem.size()) return std::nullopt;
    return name.substr(stem.size());
  };
  auto number = [&](const std::string& text) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || !(v > 0)) throw InputError("problem '" + name + "': '" + text + "' is not a positive number");
    return v;
  };
  if (name == "hnw") return hairer_wanner_problem();
  if (name == "b1") return detest_b1_problem();
  if (name == "heat") return heat_problem(n);
  if (auto k = suffix("heat")) return heat_problem(Eigen::Index(number(*k)));
  if (name == "vdp") return van_der_pol_problem(1e3);
  if (auto mu = suffix("vdp")) {
    OdeProblem p = van_der_pol_problem(number(*mu));
    p.name = name;
    return p;
  }
  if (name == "robertson") return robertson_problem();
  if (name == "hires") return hires_problem();
  if (name == "orego") return oregonator_problem();
  if (name == "e5") return e5_problem();
  if (name == "pollu") return pollution_problem();
  throw InputError("unknown problem '" + name + "' (" + builtin_problem_names + ")");
}

}  // namespace mbsflow
