#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>

#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {
// Largest |eigenvalue| of the Jacobian of the right-hand side, by central differences.
double spectral_radius(MultibodySystem& sys, const Eigen::VectorXd& y) {
  const Eigen::Index n = sys.dimension();
  Eigen::MatrixXd jac(n, n);
  Eigen::VectorXd f1(n), f2(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::VectorXd a = y, b = y;
    const double h = 1e-7 * std::max(1.0, std::abs(y[i]));
    a[i] -= h;
    b[i] += h;
    sys.rhs(0.0, a, f1);
    sys.rhs(0.0, b, f2);
    jac.col(i) = (f2 - f1) / (2 * h);
  }
  return Eigen::EigenSolver<Eigen::MatrixXd>(jac, false).eigenvalues().cwiseAbs().maxCoeff();
}
}  // namespace

TEST_CASE("stable-step estimate bounds the fastest eigenvalue, not too loosely", "[graph]") {
  for (double zeta : {0.0, 0.3}) {
    ChainParams p;
    p.bodies = 6;
    p.damping_ratio = zeta;
    const Model model = make_chain(p);
    MultibodySystem sys(model);
    const double rho = spectral_radius(sys, sys.initial_state());
    const StableStep s = estimate_stable_step(model);
    INFO("zeta " << zeta << ": spectral radius " << rho << ", bound " << s.lambda_max);
    CHECK(s.lambda_max >= rho);
    CHECK(s.lambda_max < 3.0 * rho);
    CHECK(s.step == Approx(rk4_stability_radius / s.lambda_max));
    CHECK(model.joints[static_cast<std::size_t>(s.joint)].name.size() > 0);
  }
}

TEST_CASE("RK4 at the estimated step stays bounded, far above it it blows up", "[graph]") {
  ChainParams p;
  p.bodies = 6;
  p.damping_ratio = 0.0;
  p.rotational_stiffness = 50.0;
  const Model model = make_chain(p);
  MultibodySystem sys(model);
  const double h = estimate_stable_step(model).step;
  const Eigen::VectorXd y = integrate_rk4(sys, 4000 * h, 4000);
  CHECK(y.allFinite());
  CHECK(y.segment(sys.layout().velocity(0), 3 * 6).cwiseAbs().maxCoeff() < 100.0);
  const Eigen::VectorXd z = integrate_rk4(sys, 4000 * 3 * h, 4000);
  CHECK_FALSE((z.allFinite() && z.segment(sys.layout().velocity(0), 3 * 6).cwiseAbs().maxCoeff() < 100.0));
}
