// Three more stiff problems of the Test Set for IVP Solvers (Mazzia, Magherini et al.,
// Bari; Hairer & Wanner II): HIRES, OREGO and E5, each with its exact Jacobian, its
// published y(t_end) and the absolute scale the test set's runs use.
#include <Eigen/Dense>
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

// The Oregonator's and E5's constants.
namespace orego {
constexpr double s = 77.27, w = 0.161, q = 8.375e-6;
}
namespace e5 {
constexpr double a = 7.89e-10, b = 1.1e7, c = 1.13e3, m = 1e6;
}

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

}  // namespace mbsflow
