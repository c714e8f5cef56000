// Embedding mbsflow's implicit methods: a user's stiff ODE system (Robertson's chemical
// kinetics) integrated with a collocation block method and the seed's step control. No
// Jacobian is given: Newton takes it by finite differences.
// usage: ode_example      exit code 0 if the mass is conserved and y1(40) is right
#include <cmath>
#include <cstdio>

#include <mbsflow/methods/block_integrator.hpp>

int main() {
  Eigen::VectorXd y0(3);
  y0 << 1, 0, 0;
  mbsflow::OdeProblem robertson = mbsflow::make_ode_problem(
      "robertson", 0.0, 40.0, y0, [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
        dy(0) = -0.04 * y(0) + 1e4 * y(1) * y(2);
        dy(1) = 0.04 * y(0) - 1e4 * y(1) * y(2) - 3e7 * y(1) * y(1);
        dy(2) = 3e7 * y(1) * y(1);
      });
  mbsflow::BlockSettings settings;
  settings.method = {1, 2, 2};  // s = 2 at order 2: Radau-type, L-stable
  settings.rtol = 1e-6;
  settings.atol = 1e-10;
  double worst_mass = 0;  // y1 + y2 + y3 = 1 is conserved
  const mbsflow::BlockResult r = mbsflow::integrate_block(robertson, settings, [&](const mbsflow::AcceptedBlock& b) {
    for (const Eigen::VectorXd& y : *b.u) worst_mass = std::max(worst_mass, std::abs(y.sum() - 1));
  });
  const double reference = 0.7158270687193267;  // y1(40), Hairer & Wanner
  std::printf("robertson: y1(40) = %.10f (reference %.10f), mass error %.1e, %ld blocks, %ld f evaluations\n", r.y(0),
              reference, worst_mass, r.stats.accepted, r.stats.rhs_evaluations);
  return std::abs(r.y(0) - reference) < 1e-4 && worst_mass < 1e-9 ? 0 : 1;
}
