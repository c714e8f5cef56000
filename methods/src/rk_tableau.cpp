// The tableaux: Gauss and Radau IIA as collocation methods at the roots of (shifted)
// Legendre polynomials, computed in long double; Lobatto IIIC exactly; the one-step block
// methods of seed 001 rewritten as Runge-Kutta methods.
#include "mbsflow/methods/real_eigen.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/rk_tableau.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <optional>

#include "mbsflow/methods/block_method.hpp"

namespace mbsflow {
namespace {

using Real = long double;
using MatrixR = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
using VectorR = Eigen::Matrix<Real, Eigen::Dynamic, 1>;

// P_n(y), the Legendre polynomial, by its three-term recurrence.
Real legendre(int n, Real y) {
  Real p0 = 1, p1 = y;
  if (n == 0) return p0;
  for (int k = 1; k < n; ++k) {
    const Real p2 = ((2 * k + 1) * y * p1 - k * p0) / (k + 1);
    p0 = p1;
    p1 = p2;
  }
  return p1;
}

// The roots in [0, 1] of g(2x - 1), all simple: sign changes on a fine grid, then
// bisection to the last bit; an exact zero at x = 1 counts.
template <class G>
std::vector<Real> roots_on_unit_interval(G g, int expected) {
  std::vector<Real> roots;
  const int grid = 4000;
  auto at = [&](Real x) { return g(2 * x - 1); };
  Real x0 = 0, g0 = at(x0);
  for (int k = 1; k <= grid; ++k) {
    const Real x1 = Real(k) / grid, g1 = at(x1);
    if (g1 == 0 && k == grid) {
      roots.push_back(1);
    } else if ((g0 < 0) != (g1 < 0) && g1 != 0) {
      Real lo = x0, hi = x1, glo = g0;
      for (int it = 0; it < 200 && hi - lo > 0; ++it) {
        const Real mid = (lo + hi) / 2;
        if (mid == lo || mid == hi) break;
        const Real gm = at(mid);
        if ((gm < 0) == (glo < 0)) {
          lo = mid;
          glo = gm;
        } else {
          hi = mid;
        }
      }
      roots.push_back((lo + hi) / 2);
    }
    x0 = x1;
    g0 = g1;
  }
  if (static_cast<int>(roots.size()) != expected) throw std::logic_error("collocation nodes: wrong number of roots");
  return roots;
}

// The collocation method at nodes c: C(s) gives A = R W^-1 with W_jk = c_j^(k-1),
// R_ik = c_i^k / k, and B(s) gives b.
RkTableau collocation(const std::vector<Real>& nodes) {
  const int s = static_cast<int>(nodes.size());
  MatrixR w(s, s), r(s, s);
  VectorR q(s);
  for (int j = 0; j < s; ++j)
    for (int k = 0; k < s; ++k) {
      w(j, k) = std::pow(nodes[j], Real(k));
      r(j, k) = std::pow(nodes[j], Real(k + 1)) / (k + 1);
    }
  for (int k = 0; k < s; ++k) q(k) = Real(1) / (k + 1);
  const Eigen::FullPivLU<MatrixR> lu(w);
  const MatrixR winv = lu.inverse();
  RkTableau t;
  t.a = (r * winv).cast<double>();
  t.b = (q.transpose() * winv).transpose().cast<double>();
  t.c.resize(s);
  for (int j = 0; j < s; ++j) t.c(j) = static_cast<double>(nodes[j]);
  return t;
}

RkTableau gauss(int s) {
  RkTableau t = collocation(roots_on_unit_interval([s](Real y) { return legendre(s, y); }, s));
  t.name = "gauss" + std::to_string(s);
  t.family = "Gauss (collocation at the Gauss-Legendre points)";
  t.order = 2 * s;
  return t;
}


RkTableau lobatto3c() {
  RkTableau t;
  t.name = "lobatto3c";
  t.family = "Lobatto IIIC, 3 stages";
  t.order = 4;
  t.a.resize(3, 3);
  t.a << 1.0 / 6, -1.0 / 3, 1.0 / 6,  //
      1.0 / 6, 5.0 / 12, -1.0 / 12,    //
      1.0 / 6, 2.0 / 3, 1.0 / 6;
  t.b = t.a.row(2).transpose();
  t.c.resize(3);
  t.c << 0, 0.5, 1;
  return t;
}

// The s-point one-step block method of maximal order s + 1 as an (s+1)-stage method over
// the whole block (step s tau): stage 0 is the block start, stage i the point t0 + i tau.
RkTableau block(int s) {
  const BlockCoefficients m = generate_block_method({1, s, 0});
  RkTableau t;
  t.name = "block" + std::to_string(s);
  t.family = "one-step collocation block method (seed 001), " + std::to_string(s) + " equispaced points";
  // Stage order s + 1; at the block end the symmetric nodes give the next even order
  // (as for Lobatto IIIA): s + 2 for even s.
  t.order = m.order % 2 == 0 ? m.order : m.order + 1;
  t.a = Eigen::MatrixXd::Zero(s + 1, s + 1);
  for (int i = 0; i < s; ++i) {
    t.a(i + 1, 0) = m.d(i, 0) / s;
    for (int j = 0; j < s; ++j) t.a(i + 1, j + 1) = m.g(i, j) / s;
  }
  t.b = t.a.row(s).transpose();
  t.c = Eigen::VectorXd::LinSpaced(s + 1, 0.0, 1.0);
  t.explicit_first = true;
  return t;
}

}  // namespace

RkTableau radau_iia(int s) {
  if (s < 1 || s > 12) throw InputError("Radau IIA: stages must be in 1..12 (got " + std::to_string(s) + ")");
  // Computed once per s: the roots in extended precision were 44 % of setting up a colloc
  // solve (about 0.1 ms), which a small problem pays on every call.
  static std::mutex made;
  static std::array<std::optional<RkTableau>, 13> tableaux;
  const std::lock_guard<std::mutex> lock(made);
  std::optional<RkTableau>& t = tableaux[static_cast<std::size_t>(s)];
  if (!t) {
    t = collocation(roots_on_unit_interval([s](Real y) { return legendre(s, y) - legendre(s - 1, y); }, s));
    t->name = "radau" + std::to_string(s);
    t->family = "Radau IIA (collocation at the right Radau points)";
    t->order = 2 * s - 1;
  }
  return *t;
}

Eigen::MatrixXd RkTableau::implicit_block() const {
  const int k = first_implicit(), n = implicit_stages();
  return a.block(k, k, n, n);
}

TriangularSplitting ldu_splitting(const Eigen::MatrixXd& a) {
  const Eigen::Index n = a.rows();
  TriangularSplitting s;
  s.l = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd upper = a;  // Doolittle elimination without pivoting
  const double scale = std::max(1e-300, a.cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < n; ++k) {
    if (std::abs(upper(k, k)) <= 1e-13 * scale)
      throw InputError("the matrix has no LDU factorisation without pivoting (leading minor " + std::to_string(k + 1) +
                                  " vanishes)");
    for (Eigen::Index i = k + 1; i < n; ++i) {
      s.l(i, k) = upper(i, k) / upper(k, k);
      upper.row(i) -= s.l(i, k) * upper.row(k);
      upper(i, k) = 0;
    }
  }
  s.d = upper.diagonal();
  s.diagonal = s.d.asDiagonal();
  s.u = s.d.cwiseInverse().asDiagonal() * upper;
  s.u.diagonal().setOnes();  // exactly, not d_i / d_i rounded
  s.t_lower = s.l * s.diagonal;
  s.t_upper = s.u;
  s.reconstruction_error = (s.t_lower * s.t_upper - a).cwiseAbs().maxCoeff();
  const Eigen::MatrixXd seed = s.l - Eigen::MatrixXd::Identity(n, n) + s.diagonal;
  s.seed_formula_error = (seed * s.t_upper - a).cwiseAbs().maxCoeff();
  return s;
}

EmbeddedFormula embedded_formula(const RkTableau& t, const TriangularSplitting& split) {
  return embedded_formula(t, split.d.maxCoeff());
}

double largest_real_eigenvalue(const RkTableau& t) {
  const Eigen::VectorXcd mu = eigenvalues_of(t.implicit_block());
  double best = 0;
  for (const std::complex<double>& m : mu)
    if (std::abs(m.imag()) <= 1e-12 * std::max(1.0, std::abs(m))) best = std::max(best, m.real());
  return best;
}

EmbeddedFormula embedded_formula(const RkTableau& t, double gamma) {
  EmbeddedFormula e;
  e.gamma = gamma;
  if (!(e.gamma > 0)) throw InputError(t.name + ": no positive pivot for the embedded formula");
  const int s = t.stages();
  std::vector<double> distinct;
  for (int i = 0; i < s; ++i)
    if (std::none_of(distinct.begin(), distinct.end(), [&](double c) { return std::abs(c - t.c(i)) < 1e-12; }))
      distinct.push_back(t.c(i));
  e.order = std::min(t.order - 1, static_cast<int>(distinct.size()));
  // B(order) with gamma on f(t_n, x_n) (node 0), the weights nearest to b.
  Eigen::MatrixXd v(e.order, s);
  Eigen::VectorXd rhs(e.order);
  for (int k = 0; k < e.order; ++k) {
    for (int i = 0; i < s; ++i) v(k, i) = std::pow(t.c(i), k);
    rhs(k) = 1.0 / (k + 1) - (k == 0 ? e.gamma : 0.0);
  }
  const Eigen::MatrixXd vvt = v * v.transpose();
  e.bhat = t.b + v.transpose() * vvt.fullPivLu().solve(rhs - v * t.b);
  return e;
}

RkTableau rk_tableau(const std::string& name) {
  if (name.rfind("radau", 0) == 0 && name.size() > 5 && name.size() <= 7 &&
      name.find_first_not_of("0123456789", 5) == std::string::npos) {
    const int s = std::stoi(name.substr(5));
    if (s >= 1 && s <= 12) return radau_iia(s);
  }
  if (name == "gauss2") return gauss(2);
  if (name == "gauss3") return gauss(3);
  if (name == "lobatto3c") return lobatto3c();
  if (name.size() == 6 && name.rfind("block", 0) == 0 && name[5] >= '1' && name[5] <= '6') return block(name[5] - '0');
  std::string all;
  for (const std::string& n : rk_tableau_names()) all += (all.empty() ? "" : ", ") + n;
  throw InputError("unknown tableau '" + name + "' (" + all + ")");
}

std::vector<std::string> rk_tableau_names() {
  return {"radau2", "radau3", "radau5", "gauss2", "gauss3", "lobatto3c", "block1", "block2", "block3", "block4", "block5", "block6"};
}

double quadrature_residual(const RkTableau& t, int order) {
  double r = 0;
  for (int k = 1; k <= order; ++k) r = std::max(r, std::abs(t.b.dot(t.c.array().pow(k - 1).matrix()) - 1.0 / k));
  return r;
}

double stage_order_residual(const RkTableau& t, int stage_order) {
  double r = 0;
  for (int k = 1; k <= stage_order; ++k) {
    const Eigen::VectorXd lhs = t.a * t.c.array().pow(k - 1).matrix();
    r = std::max(r, (lhs.array() - t.c.array().pow(k) / k).abs().maxCoeff());
  }
  return r;
}

std::complex<double> stability_value(const RkTableau& t, std::complex<double> z) {
  using C = std::complex<long double>;
  using MatrixC = Eigen::Matrix<C, Eigen::Dynamic, Eigen::Dynamic>;
  using VectorC = Eigen::Matrix<C, Eigen::Dynamic, 1>;
  const int s = t.stages();
  const C zl(z.real(), z.imag());
  const MatrixC m = MatrixC::Identity(s, s) - zl * t.a.cast<long double>().cast<C>();
  const VectorC w = m.fullPivLu().solve(VectorC::Ones(s));
  const C r = C(1) + zl * (t.b.cast<long double>().cast<C>().dot(w));
  return {static_cast<double>(r.real()), static_cast<double>(r.imag())};
}

bool stiffly_accurate(const RkTableau& t) {
  const int last = t.stages() - 1;
  return t.c(last) == 1.0 && (t.a.row(last).transpose() - t.b).cwiseAbs().maxCoeff() < 1e-15;
}

StabilityReport check_a_stability(const RkTableau& t) {
  double at_infinity;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(t.a);
  if (lu.isInvertible()) {
    at_infinity = std::abs(1.0 - t.b.dot(lu.solve(Eigen::VectorXd::Ones(t.stages()))));  // R(inf) = 1 - b^T A^-1 1
  } else {
    at_infinity = std::abs(stability_value(t, -1e10));  // an explicit stage: the limit numerically
  }
  if (at_infinity < 1e-12) at_infinity = 0;
  return stability_report([&](std::complex<double> z) { return stability_value(t, z); },
                          t.a, at_infinity);
}

}  // namespace mbsflow
