// Four more stiff problems of the Test Set for IVP Solvers (Mazzia, Magherini et al.,
// Bari; Hairer & Wanner II): HIRES, OREGO, E5 and POLLU, each with its exact Jacobian, its
// published y(t_end) and the absolute scale the test set's runs use.
#include <Eigen/Dense>
#include <initializer_list>
#include <utility>
#include <vector>

#include "mbsflow/methods/ode_problem.hpp"

namespace mbsflow {
namespace {

// A small problem's Jacobian from a dense one, every entry stored (zeros too): the pattern
// stays the same from one evaluation to the next.
template <class F>
void set_dense_jacobian(OdeProblem& p, F dense) {
  p.jacobian = [dense](double t, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& j) {
    const Eigen::MatrixXd d = dense(t, y);
    std::vector<Eigen::Triplet<double>> e;
    e.reserve(static_cast<std::size_t>(d.size()));
    for (Eigen::Index c = 0; c < d.cols(); ++c)
      for (Eigen::Index r = 0; r < d.rows(); ++r) e.emplace_back(r, c, d(r, c));
    j.resize(d.rows(), d.cols());
    j.setFromTriplets(e.begin(), e.end());
  };
}

}  // namespace

OdeProblem hires_problem() {
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(8);
  y0(0) = 1;
  y0(7) = 0.0057;
  OdeProblem p = make_ode_problem("hires", 0, 321.8122, y0, [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    const double r = 280 * y(5) * y(7);
    dy(0) = -1.71 * y(0) + 0.43 * y(1) + 8.32 * y(2) + 0.0007;
    dy(1) = 1.71 * y(0) - 8.75 * y(1);
    dy(2) = -10.03 * y(2) + 0.43 * y(3) + 0.035 * y(4);
    dy(3) = 8.32 * y(1) + 1.71 * y(2) - 1.12 * y(3);
    dy(4) = -1.745 * y(4) + 0.43 * y(5) + 0.43 * y(6);
    dy(5) = -r + 0.69 * y(3) + 1.71 * y(4) - 0.43 * y(5) + 0.69 * y(6);
    dy(6) = r - 1.81 * y(6);
    dy(7) = -r + 1.81 * y(6);
  });
  set_dense_jacobian(p, [](double, const Eigen::VectorXd& y) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(8, 8);
    j(0, 0) = -1.71, j(0, 1) = 0.43, j(0, 2) = 8.32;
    j(1, 0) = 1.71, j(1, 1) = -8.75;
    j(2, 2) = -10.03, j(2, 3) = 0.43, j(2, 4) = 0.035;
    j(3, 1) = 8.32, j(3, 2) = 1.71, j(3, 3) = -1.12;
    j(4, 4) = -1.745, j(4, 5) = 0.43, j(4, 6) = 0.43;
    j(5, 3) = 0.69, j(5, 4) = 1.71, j(5, 5) = -0.43 - 280 * y(7), j(5, 6) = 0.69, j(5, 7) = -280 * y(5);
    j(6, 5) = 280 * y(7), j(6, 6) = -1.81, j(6, 7) = 280 * y(5);
    j(7, 5) = -280 * y(7), j(7, 6) = 1.81, j(7, 7) = -280 * y(5);
    return j;
  });
  p.absolute_scale = Eigen::VectorXd::Constant(8, 1e-4);  // the test set's atol = 1e-4 rtol
  p.end_reference.resize(8);
  p.end_reference << 0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4, 0.1175651343283149e-2,
      0.2386356198831331e-2, 0.6238968252742796e-2, 0.2849998395185769e-2, 0.2850001604814231e-2;
  p.end_reference_source = "Test Set for IVP Solvers, problem HIRES";
  return p;
}

namespace {
// The Oregonator's and E5's constants.
namespace orego {
constexpr double s = 77.27, w = 0.161, q = 8.375e-6;
}
namespace e5 {
constexpr double a = 7.89e-10, b = 1.1e7, c = 1.13e3, m = 1e6;
}
}  // namespace

OdeProblem oregonator_problem() {
  using namespace orego;
  OdeProblem p = make_ode_problem("orego", 0, 360, Eigen::Vector3d(1, 2, 3), [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    dy(0) = s * (y(1) - y(0) * y(1) + y(0) - q * y(0) * y(0));
    dy(1) = (-y(1) - y(0) * y(1) + y(2)) / s;
    dy(2) = w * (y(0) - y(2));
  });
  set_dense_jacobian(p, [](double, const Eigen::VectorXd& y) {
    Eigen::MatrixXd j(3, 3);
    j << s * (1 - y(1) - 2 * q * y(0)), s * (1 - y(0)), 0,  //
        -y(1) / s, -(1 + y(0)) / s, 1 / s,                   //
        w, 0, -w;
    return j;
  });
  p.end_reference = Eigen::Vector3d(0.1000814870318523e1, 0.1228178521549917e4, 0.1320554942846706e3);
  p.end_reference_source = "Test Set for IVP Solvers, problem OREGO";
  return p;
}

OdeProblem e5_problem() {
  using namespace e5;
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(4);
  y0(0) = 1.76e-3;
  OdeProblem p = make_ode_problem("e5", 0, 1e13, y0, [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    const double r1 = a * y(0), r2 = b * y(0) * y(2), r3 = m * c * y(1) * y(2), r4 = c * y(3);
    dy(0) = -r1 - r2;
    dy(1) = r1 - r3;
    dy(3) = r2 - r4;
    dy(2) = dy(1) - dy(3);  // as the test set writes it: A y1 - B y1 y3 - M C y2 y3 + C y4
  });
  set_dense_jacobian(p, [](double, const Eigen::VectorXd& y) {
    Eigen::MatrixXd j(4, 4);
    j << -a - b * y(2), 0, -b * y(0), 0,                                     //
        a, -m * c * y(2), -m * c * y(1), 0,                                  //
        a - b * y(2), -m * c * y(2), -m * c * y(1) - b * y(0), c,            //
        b * y(2), 0, b * y(0), -c;
    return j;
  });
  // y2..y4 stay below 1e-13 and y1 ends near 1e-290: the test set runs it at atol 1.7e-24.
  p.absolute_scale = Eigen::VectorXd::Constant(4, 1e-20);
  p.end_reference.resize(4);
  p.end_reference << 0.1152903278711829e-290, 0.8867655517642120e-22, 0.8854814626268838e-22, 0.0;
  p.end_reference_source = "Test Set for IVP Solvers, problem E5";
  return p;
}

namespace {

// A mass-action reaction: rate k times the product of its reactants, and what it does to
// each species (stoichiometric coefficient).
struct Reaction {
  double k;
  std::vector<int> reactants;
  std::vector<std::pair<int, double>> effect;
  double rate(const Eigen::VectorXd& y) const {
    double r = k;
    for (int i : reactants) r *= y(i);
    return r;
  }
  // d rate / d y_j, j one of the reactants.
  double slope(const Eigen::VectorXd& y, int j) const {
    double r = k;
    bool skipped = false;
    for (int i : reactants) {
      if (i == j && !skipped) {
        skipped = true;
        continue;
      }
      r *= y(i);
    }
    return r;
  }
};

// POLLU's 25 reactions on 20 species (the test set numbers them from 1; here from 0).
std::vector<Reaction> pollution_reactions() {
  const auto r = [](double k, std::initializer_list<int> in, std::initializer_list<std::pair<int, double>> out) {
    Reaction x{k, {}, {}};
    for (int i : in) x.reactants.push_back(i - 1);
    for (auto [i, c] : out) x.effect.emplace_back(i - 1, c);
    return x;
  };
  return {r(0.35, {1}, {{1, -1}, {2, 1}, {3, 1}}),
          r(26.6, {2, 4}, {{1, 1}, {2, -1}, {4, -1}}),
          r(1.23e4, {5, 2}, {{1, 1}, {2, -1}, {5, -1}, {6, 1}}),
          r(8.6e-4, {7}, {{5, 2}, {7, -1}, {8, 1}}),
          r(8.2e-4, {7}, {{7, -1}, {8, 1}}),
          r(1.5e4, {7, 6}, {{5, 1}, {6, -1}, {7, -1}, {8, 1}}),
          r(1.3e-4, {9}, {{5, 1}, {8, 1}, {9, -1}, {10, 1}}),
          r(2.4e4, {9, 6}, {{6, -1}, {9, -1}, {11, 1}}),
          r(1.65e4, {11, 2}, {{1, 1}, {2, -1}, {10, 1}, {11, -1}, {12, 1}}),
          r(9.0e3, {11, 1}, {{1, -1}, {11, -1}, {13, 1}}),
          r(2.2e-2, {13}, {{1, 1}, {11, 1}, {13, -1}}),
          r(1.2e4, {10, 2}, {{1, 1}, {2, -1}, {10, -1}, {14, 1}}),
          r(1.88, {14}, {{5, 1}, {7, 1}, {14, -1}}),
          r(1.63e4, {1, 6}, {{1, -1}, {6, -1}, {15, 1}}),
          r(4.8e6, {3}, {{3, -1}, {4, 1}}),
          r(3.5e-4, {4}, {{4, -1}, {16, 1}}),
          r(1.75e-2, {4}, {{3, 1}, {4, -1}}),
          r(1.0e8, {16}, {{6, 2}, {16, -1}}),
          r(4.44e11, {16}, {{3, 1}, {16, -1}}),
          r(1.24e3, {17, 6}, {{5, 1}, {6, -1}, {17, -1}, {18, 1}}),
          r(2.1, {19}, {{2, 1}, {19, -1}}),
          r(5.78, {19}, {{1, 1}, {3, 1}, {19, -1}}),
          r(4.74e-2, {1, 4}, {{1, -1}, {4, -1}, {19, 1}}),
          r(1.78e3, {19, 1}, {{1, -1}, {19, -1}, {20, 1}}),
          r(3.12, {20}, {{1, 1}, {19, 1}, {20, -1}})};
}

}  // namespace

OdeProblem pollution_problem() {
  const std::vector<Reaction> reactions = pollution_reactions();
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(20);
  y0(1) = 0.2, y0(3) = 0.04, y0(6) = 0.1, y0(7) = 0.3, y0(8) = 0.01, y0(16) = 0.007;
  OdeProblem p = make_ode_problem("pollu", 0, 60, y0, [reactions](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    dy.setZero();
    for (const Reaction& r : reactions) {
      const double rate = r.rate(y);
      for (auto [i, c] : r.effect) dy(i) += c * rate;
    }
  });
  set_dense_jacobian(p, [reactions](double, const Eigen::VectorXd& y) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(20, 20);
    for (const Reaction& r : reactions)
      for (int k : r.reactants) {
        const double slope = r.slope(y, k);
        for (auto [i, c] : r.effect) j(i, k) += c * slope;
      }
    return j;
  });
  // Components from 0.3 down to 4e-18 (y16): held in absolute terms below 1e-12 of rtol's scale.
  p.absolute_scale = Eigen::VectorXd::Constant(20, 1e-12);
  p.end_reference.resize(20);
  p.end_reference << 0.5646255480022769e-1, 0.1342484130422339e+0, 0.4139734331099427e-8, 0.5523140207484359e-2,
      0.2018977262302196e-6, 0.1464541863493966e-6, 0.7784249118997964e-1, 0.3245075353396018e+0, 0.7494013383880406e-2,
      0.1622293157301561e-7, 0.1135863833257075e-7, 0.2230505975721359e-2, 0.2087162882798630e-3, 0.1396921016840158e-4,
      0.8964884856898061e-2, 0.4352846369330103e-17, 0.6899219696263405e-2, 0.1007803037365946e-3, 0.1772146513969984e-5,
      0.5682943292316392e-4;
  p.end_reference_source = "Test Set for IVP Solvers, problem POLLU";
  return p;
}

}  // namespace mbsflow
