// Embedding mbsflow: a model built in C++ (no JSON), a user-defined force element,
// a run written to HDF5, and the results read back.
//
// Five blocks joined by bushings hang from a beam and swing down onto a floor; the floor
// is not part of the model format, so it comes in as a ForceElement (penalty contact).
// usage: embed_example RESULTS.h5      exit code 0 if the results make physical sense
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <mbsflow/graph/force_element.hpp>
#include <mbsflow/graph/model.hpp>
#include <mbsflow/graph/multibody_system.hpp>
#include <mbsflow/io/hdf5_sink.hpp>
#include <mbsflow/io/results_file.hpp>
#include <mbsflow/runtime/async_sink.hpp>
#include <mbsflow/runtime/simulation.hpp>

namespace {

// A floor at height y = level pushing on every body's centre with a spring-damper.
class Floor : public mbsflow::ForceElement {
 public:
  Floor(int bodies, double level) : bodies_(bodies), level_(level) {}
  std::vector<int> bodies() const override {
    std::vector<int> b(static_cast<std::size_t>(bodies_));
    for (int i = 0; i < bodies_; ++i) b[static_cast<std::size_t>(i)] = i;
    return b;
  }
  void evaluate(double, const mbsflow::Kinematics& k, std::span<mbsflow::Wrench> out) const override {
    for (int i = 0; i < bodies_; ++i) {
      const double depth = level_ - k.position(i).y();
      mbsflow::Wrench& w = out[static_cast<std::size_t>(i)];
      w = {};
      if (depth > 0.0) w.force.y() = std::max(0.0, stiffness * depth - damping * k.velocity(i).y());
    }
  }
  double energy(double, const mbsflow::Kinematics& k) const override {
    double e = 0.0;
    for (int i = 0; i < bodies_; ++i) e += 0.5 * stiffness * std::pow(std::max(0.0, level_ - k.position(i).y()), 2);
    return e;
  }
  static constexpr double stiffness = 2e5, damping = 500.0;

 private:
  int bodies_;
  double level_;
};

mbsflow::Model build_model() {
  mbsflow::Model m;
  m.name = "blocks-on-a-floor";
  m.gravity = {0.0, -9.81, 0.0};
  for (int i = 0; i < 5; ++i) {
    mbsflow::Body b;
    b.name = "block" + std::to_string(i);
    b.mass = 2.0;
    b.inertia = {0.02, 0.02, 0.02, 0.0, 0.0, 0.0};
    b.position = {0.3 * (i + 1), 1.0, 0.0};
    m.bodies.push_back(b);
    mbsflow::Joint j;
    j.name = "link" + std::to_string(i);
    j.body1 = i == 0 ? mbsflow::ground : i - 1;
    j.body2 = i;
    j.point1 = i == 0 ? mbsflow::Vec3{0.15, 1.0, 0.0} : mbsflow::Vec3{0.15, 0.0, 0.0};
    j.point2 = {-0.15, 0.0, 0.0};
    mbsflow::set_bushing_from_frequency(m, j, 150.0, 0.05);  // the seed's (Omega, mu) form
    for (std::size_t a = 3; a < 6; ++a) {  // free to swing
      j.stiffness.set(a, 0.0);
      j.damping.set(a, 0.0);
    }
    m.joints.push_back(j);
  }
  m.simulation.t_end = 3.0;
  m.simulation.step = 2e-4;
  m.simulation.output_every = 50;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "embed.h5";
  const double floor_level = 0.2;
  const mbsflow::Model model = build_model();
  mbsflow::MultibodySystem system(model);
  system.add_force_element(std::make_shared<Floor>(static_cast<int>(model.bodies.size()), floor_level));
  const mbsflow::RunOptions options = mbsflow::options_from_model(model);
  mbsflow::RunInfo info;
  info.method = mbsflow::method_name(options.method);
  info.step = options.step;
  info.t_end = options.t_end;
  info.output_every = options.output_every;
  info.command_line = "embed_example";
  mbsflow::AsyncSink sink(std::make_unique<mbsflow::Hdf5Sink>(out, mbsflow::FieldSet{}, info));
  const mbsflow::RunSummary run = mbsflow::run_simulation(system, options, &sink);
  std::printf("%ld steps in %.3f s, %ld snapshots written to %s\n", run.steps, run.wall_seconds, run.snapshots, out.c_str());

  // Read the results back and check them: no block sinks into the floor (the contact
  // stiffness allows a few millimetres), the free end finishes on the floor, and the
  // motion lost energy to damping.
  const mbsflow::ResultsFile results(out);
  const std::vector<double> time = results.time(), energy = results.read("/energy");
  const std::vector<std::string> names = results.body_names();
  bool ok = time.size() == static_cast<std::size_t>(run.snapshots) && time.back() == options.t_end;
  for (std::size_t b = 0; b < names.size(); ++b) {
    const std::vector<double> p = results.read_item("/bodies/position", b);
    const double y_end = p[p.size() - 2];
    double y_min = y_end;
    for (std::size_t t = 0; t < time.size(); ++t) y_min = std::min(y_min, p[3 * t + 1]);
    std::printf("  %-8s lowest y %.4f m, final y %.4f m\n", names[b].c_str(), y_min, y_end);
    ok = ok && y_min > floor_level - 0.05;
    if (b + 1 == names.size()) ok = ok && std::abs(y_end - floor_level) < 0.02;
  }
  auto total = [&](std::size_t t) { return energy[3 * t] + energy[3 * t + 1] + energy[3 * t + 2]; };
  std::printf("  energy %.3f J at the start, %.3f J at the end\n", total(0), total(time.size() - 1));
  ok = ok && total(time.size() - 1) < total(0);
  std::printf("%s\n", ok ? "embed example: OK" : "embed example: results are not as expected");
  return ok ? 0 : 1;
}
