// A controller in the loop: a 2 kg block hangs from a bushing; a thruster (a user force
// element with an input) lifts it to 0.5 m above its rest position, set every 10 ms.
#include <cmath>
#include <cstdio>
#include <memory>
#include <mbsflow/runtime/simulation.hpp>

struct Thruster : mbsflow::ForceElement {  // pushes body 0 up with `command` newtons
  double command = 0.0;
  std::vector<int> bodies() const override { return {0}; }
  void evaluate(double, const mbsflow::Kinematics&, std::span<mbsflow::Wrench> out) const override {
    out[0] = {Eigen::Vector3d(0.0, command, 0.0), Eigen::Vector3d::Zero()};
  }
};

int main() {
  mbsflow::Model m;
  m.gravity = {0.0, -9.81, 0.0};
  m.bodies.push_back({.name = "block", .mass = 2.0, .inertia = mbsflow::Vec6{0.1, 0.1, 0.1, 0, 0, 0}});
  mbsflow::Joint j{.name = "mount", .body2 = 0};
  mbsflow::set_bushing_from_frequency(m, j, 20.0, 0.05);  // 20 rad/s, lightly damped
  m.joints.push_back(j);
  m.simulation.method = mbsflow::Method::dopri5;
  m.simulation.step = 1e-3;
  mbsflow::Simulation sim(m);
  auto thruster = std::make_shared<Thruster>();
  sim.add_force_element(thruster);
  const double target = 0.5, k = 2.0 * 400.0, c = 2.0 * 2.0 * 0.9 * 20.0;  // PD gains: stiffer and damped
  for (int k = 1; k <= 1000; ++k) {  // 10 s at 100 Hz
    const mbsflow::BodyState b = sim.body(0);
    thruster->command = k * (target - b.position.y()) - c * b.velocity.y() + 2.0 * 9.81 + 2.0 * 400.0 * b.position.y();
    sim.inputs_changed();
    sim.advance_to(0.01 * k);
  }
  const double y = sim.body(0).position.y();
  std::printf("controller example: block at %.5f m after %g s (%ld steps); target %.2f m\n", y, sim.time(), sim.stats().accepted, target);
  return std::abs(y - target) < 1e-3 ? 0 : 1;
}
