// Generation of collocation block methods in exact rational arithmetic
// (Boost.Multiprecision's cpp_rational: header-only, part of libboost-dev).
#include "mbsflow/error.hpp"
#include "mbsflow/methods/block_method.hpp"

#include "mbsflow/methods/real_eigen.hpp"
#include <Eigen/LU>
#include <boost/multiprecision/cpp_int.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>

#include "mbsflow/methods/rk_tableau.hpp"

namespace mbsflow {
namespace {

using Rational = boost::multiprecision::cpp_rational;

std::string text(const Rational& r) {
  const auto num = boost::multiprecision::numerator(r), den = boost::multiprecision::denominator(r);
  return den == 1 ? num.str() : num.str() + "/" + den.str();
}
double to_double(const Rational& r) { return r.convert_to<double>(); }

template <class T>
T power(T x, int l) {
  T r = 1;
  for (int i = 0; i < l; ++i) r *= x;
  return r;
}

// The unknowns of a row: u-coefficients at points j = -(m-1)..0 (index 0..m-1), then
// f-coefficients at points j = -(m-1)..s (index m..2m+s-1).
int point_of(const BlockMethodSpec& spec, int unknown) {
  return unknown < spec.m ? unknown - (spec.m - 1) : unknown - spec.m - (spec.m - 1);
}

// Which unknowns a method of the spec's order keeps (see the header for the order in
// which the others are dropped).
std::vector<bool> kept_unknowns(const BlockMethodSpec& spec) {
  const int n = 2 * spec.m + spec.s;
  std::vector<bool> keep(n, true);
  int drop = spec.maximal_order() - spec.effective_order();
  for (int j = 0; j < spec.m - 1 && drop > 0; ++j, --drop) keep[j] = false;           // old u
  for (int j = spec.m; j < 2 * spec.m && drop > 0; ++j, --drop) keep[j] = false;      // old f, then f_0
  return keep;
}

// Exactness on 1, x, ..., x^q at the target x: one equation per power, one column per
// kept unknown; the block points lie at `positions` (the past points at 0, -1, ...).
template <class T>
void order_system(const BlockMethodSpec& spec, const std::vector<bool>& keep, const std::vector<T>& positions, int q,
                  const T& x, std::vector<std::vector<T>>& a, std::vector<T>& b) {
  a.assign(q + 1, {});
  b.assign(q + 1, T(0));
  for (int l = 0; l <= q; ++l) {
    for (int k = 0; k < static_cast<int>(keep.size()); ++k) {
      if (!keep[k]) continue;
      const T j = k < 2 * spec.m ? T(point_of(spec, k)) : positions[static_cast<std::size_t>(k - 2 * spec.m)];
      if (k < spec.m)
        a[l].push_back(power(j, l));
      else
        a[l].push_back(l == 0 ? T(0) : T(l) * power(j, l - 1));
    }
    b[l] = power(x, l);
  }
}

// Gaussian elimination with pivoting on the first non-zero (exact) entry.
std::vector<Rational> solve_exact(std::vector<std::vector<Rational>> a, std::vector<Rational> b) {
  const std::size_t n = b.size();
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    while (p < n && a[p][c] == 0) ++p;
    if (p == n) throw InputError("the order conditions of this block method are singular");
    std::swap(a[p], a[c]);
    std::swap(b[p], b[c]);
    for (std::size_t r = 0; r < n; ++r) {
      if (r == c || a[r][c] == 0) continue;
      const Rational f = a[r][c] / a[c][c];
      for (std::size_t k = c; k < n; ++k) a[r][k] -= f * a[c][k];
      b[r] -= f * b[c];
    }
  }
  for (std::size_t c = 0; c < n; ++c) b[c] /= a[c][c];
  return b;
}

Rational determinant(std::vector<std::vector<Rational>> a) {
  const std::size_t n = a.size();
  Rational det = 1;
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    while (p < n && a[p][c] == 0) ++p;
    if (p == n) return 0;
    if (p != c) {
      std::swap(a[p], a[c]);
      det = -det;
    }
    det *= a[c][c];
    for (std::size_t r = c + 1; r < n; ++r) {
      const Rational f = a[r][c] / a[c][c];
      for (std::size_t k = c; k < n; ++k) a[r][k] -= f * a[c][k];
    }
  }
  return det;
}

void check_spec(const BlockMethodSpec& spec) {
  if (spec.m < 1 || spec.s < 1) throw InputError("a block method needs m >= 1 and s >= 1");
  if (spec.nodes == BlockNodes::radau) {
    if (spec.m != 1) throw InputError("blocks at Radau points are one-step methods (m = 1); multistep blocks are equidistant");
    if (spec.order != 0 && spec.order != spec.maximal_order())
      throw InputError("blocks at Radau points have order 2s - 1 only (lower orders are equidistant blocks)");
    if (spec.s > 11) throw InputError("blocks at Radau points have at most 11 points (the controller also runs s + 1)");
    return;
  }
  if (spec.order < 0 || spec.order > spec.maximal_order())
    throw InputError("order " + std::to_string(spec.order) + " is outside 1.." +
                                std::to_string(spec.maximal_order()) + " (the maximal order 2m+s-1)");
  if (spec.order > 0 && spec.order < spec.s)
    throw InputError("order " + std::to_string(spec.order) + " is below s = " + std::to_string(spec.s) +
                                ": a block method of s points keeps its s f-values, so its order is at least s");
}

// The exact coefficients of all rows, row-major per kind, as rationals.
struct ExactRows {
  std::vector<Rational> q, d, g;
};
ExactRows exact_rows(const BlockMethodSpec& spec, const std::vector<bool>& keep) {
  ExactRows rows;
  const int n = 2 * spec.m + spec.s;
  for (int i = 1; i <= spec.s; ++i) {
    std::vector<std::vector<Rational>> a;
    std::vector<Rational> b;
    std::vector<Rational> positions;
    for (int j = 1; j <= spec.s; ++j) positions.emplace_back(j);
    order_system<Rational>(spec, keep, positions, spec.effective_order(), Rational(i), a, b);
    const std::vector<Rational> x = solve_exact(std::move(a), std::move(b));
    std::vector<Rational> full(n, 0);
    for (int k = 0, used = 0; k < n; ++k)
      if (keep[k]) full[k] = x[used++];
    for (int k = 0; k < n; ++k) {
      auto& to = k < spec.m ? rows.q : k < 2 * spec.m ? rows.d : rows.g;
      to.push_back(full[k]);
    }
  }
  return rows;
}

std::string decimal(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The one-step block at the s right Radau points: Radau IIA collocation, u_i = u_0 +
// tau sum_j a_ij f_j (q = 1, no f_0).
BlockCoefficients radau_block(const BlockMethodSpec& spec) {
  const RkTableau t = radau_iia(spec.s);
  BlockCoefficients c;
  c.spec = spec;
  c.order = spec.maximal_order();
  c.exact = false;
  c.keep_u = {true};
  c.keep_f.assign(static_cast<std::size_t>(spec.s + 1), true);
  c.keep_f[0] = false;
  c.q = Eigen::MatrixXd::Ones(spec.s, 1);
  c.d = Eigen::MatrixXd::Zero(spec.s, 1);
  c.g = t.a;
  c.positions = t.c;
  for (int i = 0; i < spec.s; ++i) {
    c.q_exact.push_back("1");
    c.d_exact.push_back("0");
    for (int j = 0; j < spec.s; ++j) c.g_exact.push_back(decimal(t.a(i, j)));
  }
  return c;
}

}  // namespace

const char* to_string(BlockNodes n) { return n == BlockNodes::radau ? "radau" : "equidistant"; }

BlockMethodSpec default_block_method() { return {1, 3, 0, BlockNodes::radau}; }

BlockMethodSpec parse_block_method(const std::string& v) {
  if (v.empty()) return default_block_method();
  BlockMethodSpec spec;
  char end = 0;
  if (v.rfind("radau", 0) == 0) {
    spec = default_block_method();
    if (v != "radau" && std::sscanf(v.c_str(), "radau,%d%c", &spec.s, &end) != 1)
      throw InputError("colloc: the variant is radau, radau,s, m,s or m,s,order (got '" + v + "')");
  } else {
    int order = 0;
    const int n = std::sscanf(v.c_str(), "%d,%d,%d%c", &spec.m, &spec.s, &order, &end);
    if (n != 2 && n != 3) throw InputError("colloc: the variant is radau, radau,s, m,s or m,s,order (got '" + v + "')");
    spec.order = order;
  }
  check_spec(spec);
  return spec;
}

std::string describe_block_method(const BlockMethodSpec& spec) {
  if (spec.nodes == BlockNodes::radau)
    return "Radau points, s = " + std::to_string(spec.s) + ", order " + std::to_string(spec.maximal_order());
  return "equidistant, m = " + std::to_string(spec.m) + ", s = " + std::to_string(spec.s) + ", order " +
         std::to_string(spec.effective_order());
}

BlockMethodSpec step_control_partner(const BlockMethodSpec& s) {
  return {s.m, s.s + 1, s.order > 0 ? s.order + 1 : 0, s.nodes};
}

namespace {

BlockCoefficients make_block_method(const BlockMethodSpec& spec) {
  if (spec.nodes == BlockNodes::radau) return radau_block(spec);
  BlockCoefficients c;
  c.spec = spec;
  c.order = spec.effective_order();
  c.positions = Eigen::VectorXd::LinSpaced(spec.s, 1, spec.s);
  const std::vector<bool> keep = kept_unknowns(spec);
  c.keep_u.assign(keep.begin(), keep.begin() + spec.m);
  c.keep_f.assign(keep.begin() + spec.m, keep.end());
  const ExactRows rows = exact_rows(spec, keep);
  c.q.resize(spec.s, spec.m);
  c.d.resize(spec.s, spec.m);
  c.g.resize(spec.s, spec.s);
  for (int i = 0; i < spec.s; ++i) {
    for (int j = 0; j < spec.m; ++j) {
      c.q(i, j) = to_double(rows.q[i * spec.m + j]);
      c.d(i, j) = to_double(rows.d[i * spec.m + j]);
    }
    for (int j = 0; j < spec.s; ++j) c.g(i, j) = to_double(rows.g[i * spec.s + j]);
  }
  for (const Rational& r : rows.q) c.q_exact.push_back(text(r));
  for (const Rational& r : rows.d) c.d_exact.push_back(text(r));
  for (const Rational& r : rows.g) c.g_exact.push_back(text(r));
  return c;
}

}  // namespace

BlockCoefficients generate_block_method(const BlockMethodSpec& spec) {
  check_spec(spec);
  // Made once per method: the exact rational rows and their decimal texts cost more than
  // a small problem's whole solve, and every colloc solve asks for two or three methods.
  static std::mutex made;
  static std::map<std::tuple<int, int, int, BlockNodes>, BlockCoefficients> methods;
  const std::lock_guard<std::mutex> lock(made);
  const auto key = std::make_tuple(spec.m, spec.s, spec.order, spec.nodes);
  auto it = methods.find(key);
  if (it == methods.end()) it = methods.emplace(key, make_block_method(spec)).first;
  return it->second;
}

DenseWeights dense_output_weights(const BlockCoefficients& method, double theta) {
  const BlockMethodSpec spec = method.spec;
  std::vector<bool> keep(method.keep_u);
  keep.insert(keep.end(), method.keep_f.begin(), method.keep_f.end());
  std::vector<std::vector<double>> a;
  std::vector<double> b;
  const std::vector<double> positions(method.positions.data(), method.positions.data() + method.positions.size());
  // The interpolation polynomial through the kept data (of the method's order for
  // equidistant blocks; degree s for Radau points, superconvergent at the end only).
  const int degree = static_cast<int>(std::count(keep.begin(), keep.end(), true)) - 1;
  order_system<double>(spec, keep, positions, degree, theta, a, b);
  const int n = static_cast<int>(b.size());
  Eigen::MatrixXd am(n, n);
  Eigen::VectorXd bv(n);
  for (int r = 0; r < n; ++r) {
    for (int k = 0; k < n; ++k) am(r, k) = a[r][k];
    bv(r) = b[r];
  }
  const Eigen::VectorXd x = am.fullPivLu().solve(bv);
  DenseWeights w{Eigen::VectorXd::Zero(spec.m), Eigen::VectorXd::Zero(spec.m), Eigen::VectorXd::Zero(spec.s)};
  for (int k = 0, used = 0; k < static_cast<int>(keep.size()); ++k) {
    if (!keep[k]) continue;
    const double v = x(used++);
    if (k < spec.m)
      w.wu(k) = v;
    else if (k < 2 * spec.m)
      w.wd(k - spec.m) = v;
    else
      w.wg(k - 2 * spec.m) = v;
  }
  return w;
}

// In doubles, for methods without exact coefficients (Radau points): the stage order s
// at every point, the order 2s - 1 at the end.
std::string order_condition_residual_double(const BlockCoefficients& method) {
  const int s = method.spec.s;
  double worst = 0;
  for (int i = 0; i < s; ++i) {
    const int order = i == s - 1 ? method.order : s;
    for (int l = 1; l <= order; ++l) {
      double sum = 0;
      for (int j = 0; j < s; ++j) sum += l * method.g(i, j) * std::pow(method.positions(j), l - 1);
      worst = std::max(worst, std::abs(sum - std::pow(method.positions(i), l)));
    }
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", worst);
  return buf;
}

std::string order_condition_residual(const BlockCoefficients& method) {
  if (!method.exact) return order_condition_residual_double(method);
  const BlockMethodSpec& spec = method.spec;
  Rational worst = 0;
  auto parse = [](const std::string& s) { return Rational(s); };
  for (int i = 1; i <= spec.s; ++i) {
    for (int l = 0; l <= method.order; ++l) {
      Rational sum = 0;
      for (int j = 0; j < spec.m; ++j) {
        const Rational p = Rational(j - (spec.m - 1));
        sum += parse(method.q_exact[(i - 1) * spec.m + j]) * power(p, l);
        if (l > 0) sum += Rational(l) * parse(method.d_exact[(i - 1) * spec.m + j]) * power(p, l - 1);
      }
      if (l > 0)
        for (int j = 1; j <= spec.s; ++j)
          sum += Rational(l) * parse(method.g_exact[(i - 1) * spec.s + j - 1]) * power(Rational(j), l - 1);
      const Rational residual = abs(sum - power(Rational(i), l));
      if (residual > worst) worst = residual;
    }
  }
  return text(worst);
}

namespace {

// R in doubles (long double determinants), for methods without exact coefficients.
// R(infinity) = |(g^-1 d)_s|: u = (I - z g)^-1 (1 + z d) tends to -g^-1 d.
StabilityFunction stability_function_double(const BlockCoefficients& method) {
  using MatrixL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  using VectorL = Eigen::Matrix<long double, Eigen::Dynamic, 1>;
  const int s = method.spec.s;
  const MatrixL g = method.g.cast<long double>();
  VectorL pv(s + 1), qv(s + 1);
  MatrixL vandermonde(s + 1, s + 1);
  for (int zi = 0; zi <= s; ++zi) {
    const long double z = zi;
    MatrixL a = MatrixL::Identity(s, s) - z * g;
    qv(zi) = a.determinant();
    for (int i = 0; i < s; ++i) a(i, s - 1) = 1 + z * static_cast<long double>(method.d(i, 0));
    pv(zi) = a.determinant();
    for (int k = 0; k <= s; ++k) vandermonde(zi, k) = std::pow(z, static_cast<long double>(k));
  }
  const Eigen::FullPivLU<MatrixL> lu(vandermonde);
  const VectorL pc = lu.solve(pv), qc = lu.solve(qv);
  StabilityFunction r;
  r.numerator = pc.cast<double>();
  r.denominator = qc.cast<double>();
  const double size = std::max(r.numerator.cwiseAbs().maxCoeff(), r.denominator.cwiseAbs().maxCoeff());
  for (Eigen::VectorXd* v : {&r.numerator, &r.denominator})
    for (double& c : *v)
      if (std::abs(c) < 1e-13 * size) c = 0;  // rounding of an exact zero
  for (int k = 0; k <= s; ++k) {
    r.numerator_exact.push_back(decimal(r.numerator(k)));
    r.denominator_exact.push_back(decimal(r.denominator(k)));
  }
  r.infinity = std::abs(method.g.fullPivLu().solve(method.d.col(0))(s - 1));
  if (r.infinity < 1e-12) r.infinity = 0;
  return r;
}

}  // namespace

StabilityFunction stability_function(const BlockCoefficients& method) {
  const int s = method.spec.s;
  if (method.spec.m != 1) throw InputError("a stability function is given for one-step methods (m = 1) only");
  if (!method.exact) return stability_function_double(method);
  // u = (I - z G)^{-1} (1 + z d) u0; u_s by Cramer's rule. P and Q have degree <= s: take
  // them at z = 0..s and interpolate.
  std::vector<Rational> qv, pv;
  for (int zi = 0; zi <= s; ++zi) {
    const Rational z = zi;
    std::vector<std::vector<Rational>> a(s, std::vector<Rational>(s));
    for (int i = 0; i < s; ++i)
      for (int j = 0; j < s; ++j) a[i][j] = Rational(i == j ? 1 : 0) - z * Rational(method.g_exact[i * s + j]);
    qv.push_back(determinant(a));
    for (int i = 0; i < s; ++i) a[i][s - 1] = 1 + z * Rational(method.d_exact[i]);
    pv.push_back(determinant(a));
  }
  std::vector<std::vector<Rational>> vandermonde(s + 1, std::vector<Rational>(s + 1));
  for (int zi = 0; zi <= s; ++zi)
    for (int k = 0; k <= s; ++k) vandermonde[zi][k] = power(Rational(zi), k);
  const std::vector<Rational> pc = solve_exact(vandermonde, pv), qc = solve_exact(vandermonde, qv);
  StabilityFunction r;
  r.numerator.resize(s + 1);
  r.denominator.resize(s + 1);
  for (int k = 0; k <= s; ++k) {
    r.numerator_exact.push_back(text(pc[k]));
    r.denominator_exact.push_back(text(qc[k]));
    r.numerator(k) = to_double(pc[k]);
    r.denominator(k) = to_double(qc[k]);
  }
  // The limit from the degrees of P and Q (exact zeros).
  int dp = s, dq = s;
  while (dp > 0 && pc[dp] == 0) --dp;
  while (dq > 0 && qc[dq] == 0) --dq;
  r.infinity = dp < dq ? 0.0 : dp > dq ? std::numeric_limits<double>::infinity() : std::abs(to_double(pc[dp] / qc[dq]));
  return r;
}

std::complex<double> StabilityFunction::operator()(std::complex<double> z) const {
  std::complex<double> p = 0, q = 0;
  for (Eigen::Index k = numerator.size() - 1; k >= 0; --k) p = p * z + numerator(k);
  for (Eigen::Index k = denominator.size() - 1; k >= 0; --k) q = q * z + denominator(k);
  return p / q;
}

ZeroStability check_zero_stability(const BlockCoefficients& method) {
  const int m = method.spec.m, s = method.spec.s;
  ZeroStability z;
  if (m == 1) return z;
  // The next window is the last m of (window, block): entry a is combined point s + a.
  Eigen::MatrixXd map = Eigen::MatrixXd::Zero(m, m);
  for (int a = 0; a < m; ++a) {
    const int c = s + a;
    if (c < m)
      map(a, c) = 1;
    else
      map.row(a) = method.q.row(c - m);
  }
  const Eigen::VectorXcd ev = eigenvalues_of(map);
  int principal = -1;
  for (int i = 0; i < m; ++i)
    if (principal < 0 || std::abs(ev(i) - 1.0) < std::abs(ev(principal) - 1.0)) principal = i;
  const double slack = 1e-9;
  for (int i = 0; i < m; ++i)
    if (i != principal) z.parasitic_radius = std::max(z.parasitic_radius, std::abs(ev(i)));
  z.strongly = z.parasitic_radius < 1 - slack;
  z.zero_stable = z.parasitic_radius <= 1 + slack;
  for (int i = 0; i < m; ++i)  // eigenvalues on the circle must be simple
    for (int j = i + 1; j < m; ++j)
      if (std::abs(ev(i)) > 1 - slack && std::abs(ev(i) - ev(j)) < 1e-6) z.zero_stable = false;
  return z;
}

StabilityReport check_a_stability(const BlockCoefficients& method) {
  const StabilityFunction r = stability_function(method);
  return stability_report(r, method.g, r.at_infinity());
}

}  // namespace mbsflow
