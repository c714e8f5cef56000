// Elastic beams (graph/beams.hpp) against closed forms: a cantilever's and a free-free
// beam's bending frequencies in both planes through the modes, converging as elements
// double; the static tip deflection P L^3 / (3 E I); the large-deflection cantilever (the
// elastica) under tip loads P L^2 / (E I) from 1 to 5 against its own shooting solution
// and Mattiasson's published table; energy kept by an undamped beam in free motion.
#include <catch2/catch.hpp>
#include <algorithm>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "mbsflow/analysis/equilibrium.hpp"
#include "mbsflow/analysis/modes.hpp"
#include "mbsflow/graph/beams.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "mbsflow/io/results_file.hpp"
#include "memory_sink.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

constexpr double pi = std::numbers::pi;
constexpr double L = 1.0, E = 2.1e11, G = 8.1e10, rho = 7850.0, A = 1e-4;
constexpr double Iz = 8.0e-10, Iy = 2.0 * Iz, J = 1.2e-9;  // two bending planes apart

BeamSpec beam_spec(int elements) {
  BeamSpec s;
  s.name = "beam";
  s.points = straight_beam_points({0, 0, 0}, {L, 0, 0}, elements);
  s.up = {0, 1, 0};
  s.E = E;
  s.G = G;
  s.density = rho;
  s.section = {A, Iy, Iz, J};
  return s;
}

// A model of one beam; clamped: its first node held (a driver without motion).
Model beam_model(int elements, bool clamped) {
  Model m;
  m.name = "beam";
  add_beam(m, beam_spec(elements));
  if (clamped) m.drivers.push_back(Driver{0});
  return m;
}

// The lowest `count` undamped natural frequencies (rad/s) at the initial state, rigid-body
// motions left out; `zeros` gets how many there were.
std::vector<double> frequencies(const Model& model, int count, int* zeros = nullptr) {
  MultibodySystem sys(model);
  const LinearModel lm = linearize(sys, 0.0, sys.initial_state());
  ModeOptions o;
  o.count = count + 6;
  o.damped = false;
  const Modes m = compute_modes(lm, o);
  std::vector<double> out;
  int rigid = 0;
  for (std::size_t j = 0; j < m.frequency.size(); ++j)
    if (m.rigid_body[j])
      ++rigid;
    else
      out.push_back(2 * pi * m.frequency[j]);
  if (zeros) *zeros = rigid;
  out.resize(static_cast<std::size_t>(std::min<int>(count, static_cast<int>(out.size()))));
  return out;
}

// The bending frequencies (rad/s) of both planes for the given beta L values, ascending.
std::vector<double> bending(const std::vector<double>& beta_l) {
  std::vector<double> out;
  for (double inertia : {Iy, Iz})
    for (double b : beta_l) out.push_back(b * b * std::sqrt(E * inertia / (rho * A * std::pow(L, 4))));
  std::sort(out.begin(), out.end());
  return out;
}

double worst_error(const std::vector<double>& got, const std::vector<double>& want) {
  double worst = 0;
  for (std::size_t j = 0; j < want.size(); ++j) worst = std::max(worst, std::abs(got.at(j) / want[j] - 1));
  return worst;
}

}  // namespace

TEST_CASE("a cantilever beam's bending frequencies converge to beta L = 1.8751, 4.6941, 7.8548, 10.9955 in both planes",
          "[analysis][beams]") {
  const std::vector<double> want = bending({1.8751041, 4.6940911, 7.8547574, 10.9955407});
  double previous = 1;
  for (int elements : {10, 20, 40, 80}) {
    const double error = worst_error(frequencies(beam_model(elements, true), 8), want);
    INFO(elements << " elements: worst relative error " << error);
    CHECK(error < 0.4 * previous);  // second order: a quarter per doubling, with margin
    previous = error;
  }
  CHECK(previous < 3e-3);
}

TEST_CASE("a free-free beam has six rigid-body motions and bending at beta L = 4.7300, 7.8532, 10.9956", "[analysis][beams]") {
  const std::vector<double> want = bending({4.7300408, 7.8532046, 10.9956078});
  double previous = 1;
  for (int elements : {10, 20, 40, 80}) {
    int zeros = 0;
    const double error = worst_error(frequencies(beam_model(elements, false), 6, &zeros), want);
    INFO(elements << " elements: worst relative error " << error);
    CHECK(zeros == 6);
    CHECK(error < 0.4 * previous);
    previous = error;
  }
  CHECK(previous < 4e-3);
}

namespace {

// A cantilever under a tip force P along -y (a dead load).
Model loaded_cantilever(int elements, double p) {
  Model m = beam_model(elements, true);
  Load load;
  load.body = elements;
  load.force = {0.0, -p, 0.0};
  m.loads.push_back(load);
  return m;
}

// The cantilever's tip under a tip force P along -y at static equilibrium.
Eigen::Vector3d loaded_tip(int elements, double p) {
  MultibodySystem sys(loaded_cantilever(elements, p));
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  return e.state.segment<3>(sys.layout().position(elements));
}

// The elastica of a cantilever under a vertical tip load, alpha = P L^2 / (E I): theta'' =
// -alpha cos(theta) on s in [0, 1], theta(0) = 0, theta'(1) = 0, by shooting on theta'(0)
// with RK4 in s; returns the tip's (horizontal, vertical) displacement over L.
std::pair<double, double> elastica(double alpha) {
  const int steps = 4000;
  const auto shoot = [&](double kappa0, double* x, double* y) {
    double th = 0, k = kappa0, px = 0, py = 0;
    const double h = 1.0 / steps;
    auto f = [&](double t, double kk) { return std::array<double, 4>{kk, -alpha * std::cos(t), std::cos(t), std::sin(t)}; };
    for (int i = 0; i < steps; ++i) {
      const auto a = f(th, k);
      const auto b = f(th + h / 2 * a[0], k + h / 2 * a[1]);
      const auto c = f(th + h / 2 * b[0], k + h / 2 * b[1]);
      const auto d = f(th + h * c[0], k + h * c[1]);
      th += h / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0]);
      k += h / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1]);
      px += h / 6 * (a[2] + 2 * b[2] + 2 * c[2] + d[2]);
      py += h / 6 * (a[3] + 2 * b[3] + 2 * c[3] + d[3]);
    }
    if (x) *x = px;
    if (y) *y = py;
    return k;  // theta'(1)
  };
  double lo = 0, hi = alpha;  // theta'(0) in (0, alpha]: the moment at the root is below P L
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (shoot(mid, nullptr, nullptr) > 0 ? hi : lo) = mid;
  }
  double x = 0, y = 0;
  shoot(0.5 * (lo + hi), &x, &y);
  return {1 - x, std::abs(y)};
}

}  // namespace

TEST_CASE("a cantilever's static tip deflection under a small tip load is P L^3 / (3 E I)", "[analysis][beams]") {
  const double p = 1e-4 * 3 * E * Iz / (L * L * L);  // a deflection of 1e-4 L
  for (int elements : {2, 8}) {
    const Eigen::Vector3d tip = loaded_tip(elements, p);
    INFO(elements << " elements: tip " << tip.transpose());
    // The two-node element is exact for a tip load; what is left is the geometric nonlinearity, O(1e-8).
    CHECK(-tip.y() == Approx(p * L * L * L / (3 * E * Iz)).epsilon(1e-6));
    CHECK(std::abs(tip.z()) < 1e-15);
  }
}

TEST_CASE("the elastica: a cantilever under a tip load P L^2 / (E I) = 1 .. 5 bends as the exact large-deflection solution",
          "[analysis][beams]") {
  // Mattiasson (1981), Table 1: the tip's horizontal and vertical displacement over L.
  const double table[5][2] = {{0.05643, 0.30172}, {0.16064, 0.49346}, {0.25442, 0.60325}, {0.32894, 0.66996}, {0.38763, 0.71379}};
  for (int a = 1; a <= 5; ++a) {
    const auto [u, v] = elastica(a);
    INFO("P L^2 / E I = " << a << ": shooting u/L " << u << ", v/L " << v);
    CHECK(u == Approx(table[a - 1][0]).margin(2e-5));  // the table's digits
    CHECK(v == Approx(table[a - 1][1]).margin(2e-5));
    const Eigen::Vector3d tip = loaded_tip(40, a * E * Iz / (L * L));
    INFO("40 elements: tip " << tip.transpose());
    CHECK((L - tip.x()) / L == Approx(u).margin(1e-3));
    CHECK(-tip.y() / L == Approx(v).margin(1e-3));
  }
}

TEST_CASE("an undamped free beam keeps its energy while it bends and turns", "[analysis][beams]") {
  Model m = beam_model(12, false);
  // Bending and twisting at once: the nodes' velocities vary along the beam.
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const double s = static_cast<double>(i) / 12.0;
    m.bodies[i].velocity = {0.0, 0.5 * std::cos(pi * s), 0.2 * std::sin(pi * s)};
    m.bodies[i].angular_velocity = {3.0, 0.0, 0.0};
  }
  MultibodySystem sys(m);
  const Eigen::VectorXd y0 = sys.initial_state();
  const auto total = [&](double t, const Eigen::VectorXd& y) {
    const Energy e = sys.energy(t, y);
    return e.kinetic + e.elastic;
  };
  const double e0 = total(0, y0);
  double drift = 0, most_elastic = 0;
  // The stiffest mode (axial, about 2e5 rad/s for these elements) sets the step.
  test::integrate_rk4(sys, 0.02, 20000, [&](double t, const Eigen::VectorXd& y) {
    drift = std::max(drift, std::abs(total(t, y) / e0 - 1));
    most_elastic = std::max(most_elastic, sys.energy(t, y).elastic);
  });
  INFO("energy drift " << drift << ", largest elastic energy " << most_elastic << " of " << e0);
  CHECK(most_elastic > 0.02 * e0);  // it did bend
  CHECK(drift < 1e-6);
}

TEST_CASE("a Timoshenko cantilever's tip deflection adds the shear's P L / (k G A)", "[analysis][beams]") {
  // A short, deep beam: the shear part is a tenth of the bending part.
  BeamSpec s = beam_spec(4);
  s.shear = true;
  s.section.shear_area_y = 0.8 * A;
  Model m;
  add_beam(m, s);
  m.drivers.push_back(Driver{0});
  const double p = 1e-4 * 3 * E * Iz / (L * L * L);
  Load load;
  load.body = 4;
  load.force = {0.0, -p, 0.0};
  m.loads.push_back(load);
  MultibodySystem sys(m);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  const double tip = -e.state[sys.layout().position(4) + 1];
  CHECK(tip == Approx(p * L * L * L / (3 * E * Iz) + p * L / (G * 0.8 * A)).epsilon(1e-6));
}

TEST_CASE("a beam through points on a line is the beam from one end to the other, and a curved one rests unloaded",
          "[analysis][beams]") {
  BeamSpec line = beam_spec(5);
  Model a, b;
  add_beam(a, line);
  line.points = {{0, 0, 0}, {0.2, 0, 0}, {0.4, 0, 0}, {0.6, 0, 0}, {0.8, 0, 0}, {1.0, 0, 0}};
  add_beam(b, line);
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    CHECK(a.bodies[i].mass == Approx(b.bodies[i].mass).epsilon(1e-14));
    for (int k = 0; k < 3; ++k) CHECK(a.bodies[i].position[k] == Approx(b.bodies[i].position[k]).margin(1e-15));
  }
  // A quarter circle: in its initial shape it carries no force at all.
  BeamSpec arc = beam_spec(1);
  arc.points.clear();
  for (int i = 0; i <= 12; ++i) arc.points.push_back({std::cos(pi / 2 * i / 12), std::sin(pi / 2 * i / 12), 0.0});
  arc.up = {0, 0, 1};
  Model c;
  add_beam(c, arc);
  MultibodySystem sys(c);
  // Rounding only: the elements' axial stiffness (1e8 N/m) times the points' rounding.
  CHECK(static_residual(sys, 0.0, sys.initial_state(), free_coordinates(sys)).cwiseAbs().maxCoeff() < 1e-6);
  CHECK(sys.energy(0.0, sys.initial_state()).elastic < 1e-20);
}

namespace {

// The four lowest modes of a damped cantilever of 20 elements.
Modes damped_cantilever_modes(double alpha, double beta) {
  BeamSpec s = beam_spec(20);
  s.stiffness_damping = beta;
  s.mass_damping = alpha;
  Model m;
  add_beam(m, s);
  m.drivers.push_back(Driver{0});
  REQUIRE(m.loads.size() == (alpha > 0 ? 21u : 0u));  // with alpha, a damping load on each node
  MultibodySystem sys(m);
  const LinearModel lm = linearize(sys, 0.0, sys.initial_state());
  ModeOptions o;
  o.count = 4;
  Modes modes = compute_modes(lm, o);
  REQUIRE(modes.frequency.size() == 4);
  return modes;
}

}  // namespace

TEST_CASE("stiffness-proportional damping: each mode's damping ratio is beta omega / 2", "[analysis][beams]") {
  const Modes modes = damped_cantilever_modes(0.0, 1e-4);
  for (std::size_t j = 0; j < 4; ++j) {
    const double omega = std::abs(modes.eigenvalue[j]);
    // To the dense eigensolver's accuracy on rates from 50 to 1e6 rad/s (torsion).
    CHECK(modes.damping_ratio[j] == Approx(1e-4 * omega / 2).epsilon(1e-4));
  }
}

TEST_CASE("Rayleigh damping alpha M + beta K: each mode's damping ratio is alpha / (2 omega) + beta omega / 2",
          "[analysis][beams]") {
  const Modes modes = damped_cantilever_modes(20.0, 1e-5);
  for (std::size_t j = 0; j < 4; ++j) {
    const double omega = std::abs(modes.eigenvalue[j]);
    INFO("mode " << j << ": omega " << omega);
    CHECK(modes.damping_ratio[j] == Approx(20.0 / (2 * omega) + 1e-5 * omega / 2).epsilon(1e-4));
  }
}

TEST_CASE("mass-proportional damping slows a free beam's rigid motion as exp(-alpha t), its spin too", "[analysis][beams]") {
  BeamSpec s = beam_spec(6);
  s.mass_damping = 3.0;
  Model m;
  add_beam(m, s);
  MultibodySystem sys(m);
  Eigen::VectorXd y = sys.initial_state();
  const StateLayout& l = sys.layout();
  for (Eigen::Index b = 0; b < l.bodies; ++b) {
    y.segment<3>(l.velocity(b)) = Eigen::Vector3d(0.0, 0.0, 2.0);
    y.segment<3>(l.angular_velocity(b)) = Eigen::Vector3d(1.5, 0.0, 0.0);  // about the beam's axis (each node's x)
  }
  const double t_end = 0.5;
  const long steps = 5000;
  const double h = t_end / static_cast<double>(steps);
  Eigen::VectorXd k1(y.size()), k2(y.size()), k3(y.size()), k4(y.size());
  for (long k = 0; k < steps; ++k) {  // RK4
    const double t = static_cast<double>(k) * h;
    sys.rhs(t, y, k1);
    sys.rhs(t + h / 2, y + h / 2 * k1, k2);
    sys.rhs(t + h / 2, y + h / 2 * k2, k3);
    sys.rhs(t + h, y + h * k3, k4);
    y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  for (Eigen::Index b = 0; b < l.bodies; ++b) {
    CHECK(y[l.velocity(b) + 2] == Approx(2.0 * std::exp(-3.0 * t_end)).epsilon(1e-9));
    CHECK(y[l.angular_velocity(b)] == Approx(1.5 * std::exp(-3.0 * t_end)).epsilon(1e-9));
  }
}

TEST_CASE("the results file holds each beam element's section forces: at a bent cantilever's equilibrium, the tip load",
          "[analysis][beams][io]") {
  // A large deflection (P L^2 / E I = 2): at every section the part beyond the cut carries
  // the tip load, so the section's force is the load (-P along world y) and its moment the
  // load's about the element's midpoint, whatever the element's turn.
  const int elements = 10;
  const double p = 2 * E * Iz / (L * L);
  const Model m = loaded_cantilever(elements, p);
  MultibodySystem sys(m);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  const std::string file =
      (std::filesystem::temp_directory_path() / ("mbsflow_beam_sections_" + std::to_string(::getpid()) + ".h5")).string();
  FieldSet fields;
  fields.joint_force = true;
  {
    Hdf5Sink sink(file, fields, RunInfo{"{}", "tirk", 0.1, 0.0, 1.0, 1, "test"});
    sink.begin(sys);
    Snapshot s;
    s.state = e.state;
    sys.joint_wrenches(0.0, s.state, s.joint_wrench);
    s.motor_effort = sys.motor_efforts();
    sink.write(std::move(s));
    sink.end();
  }
  const ResultsFile r(file);
  const std::vector<double> section = r.read(beam_section_force_dataset);
  REQUIRE(section.size() == 6 * elements);
  const StateLayout& l = sys.layout();
  const Eigen::Vector3d tip = e.state.segment<3>(l.position(elements));
  for (int k = 0; k < elements; ++k) {
    const Eigen::Map<const Eigen::Vector3d> force(section.data() + 6 * k), moment(section.data() + 6 * k + 3);
    // The midpoint as the second node's arm of half the element ends there (the wrench's
    // point; the first node's arm ends within the bushing's small deflection of it).
    const Joint& j = m.joints[static_cast<std::size_t>(k)];
    const double* q = e.state.data() + l.orientation(k + 1);
    const Eigen::Vector3d mid = e.state.segment<3>(l.position(k + 1)) +
                                Eigen::Quaterniond(q[0], q[1], q[2], q[3]) * Eigen::Vector3d(j.point2[0], j.point2[1], j.point2[2]);
    const Eigen::Vector3d load_moment = (tip - mid).cross(Eigen::Vector3d(0, -p, 0));
    INFO("element " << k << ": force " << force.transpose() << ", moment " << moment.transpose());
    CHECK(force.norm() == Approx(p).epsilon(1e-6));
    CHECK(moment.norm() == Approx(load_moment.norm()).epsilon(1e-6));
    if (k == 0) {  // the clamped node does not turn: the element's frame is the world's
      CHECK(force.y() == Approx(-p).epsilon(1e-6));
      CHECK(moment.z() == Approx(load_moment.z()).epsilon(1e-6));
    }
    // Bending in the x-y plane only: no out-of-plane shear, torsion or bending about y.
    CHECK(std::abs(force.z()) < 1e-9 * p);
    CHECK(std::abs(moment.x()) + std::abs(moment.y()) < 1e-9 * p * L);
  }
  // Axial tension grows towards the tip as the beam turns to hang along the load.
  CHECK(section[6 * (elements - 1)] > section[0]);
  std::filesystem::remove(file);
  std::filesystem::remove(xdmf_path(file));
}

namespace {

// A slider-crank with an elastic connecting rod (steel, 8 mm round, 0.3 m, `elements`
// elements; Young's modulus E): crank 0.15 m spun up smoothly to 150 rad/s over 0.1 s by
// a velocity motor, a 50 g slider on a prismatic guide along x, no gravity. Returns, over
// the first turn at full speed (t in [0.1, 0.15]), the largest bending deflection of the
// rod's midpoint from the chord of its ends and the largest gap between the slider and
// where a rigid rod puts it, r cos(theta) + sqrt(l^2 - r^2 sin^2(theta)).
struct CrankRun {
  double deflection = 0.0, slider_gap = 0.0;
};

CrankRun elastic_slider_crank(int elements, double young) {
  constexpr double r = 0.15, l = 0.3, d = 0.008;
  const double area = pi * d * d / 4, inertia = pi * std::pow(d, 4) / 64;
  const auto num = [](double x) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", x);
    return std::string(text);
  };
  std::string t_list, w_list;
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.1 * k / 20;
    t_list += (k ? ", " : "") + num(t);
    w_list += (k ? ", " : "") + num(150.0 * 0.5 * (1 - std::cos(pi * t / 0.1)));
  }
  const std::string n = std::to_string(elements);
  const std::string text = R"({"name": "elastic_slider_crank", "gravity": [0, 0, 0],
    "bodies": [{"name": "crank", "mass": 0.1, "inertia": [1e-5, 2e-4, 2e-4], "position": [0.075, 0, 0]},
               {"name": "slider", "mass": 0.05, "inertia": [1e-5, 1e-5, 1e-5], "position": [0.45, 0, 0]}],
    "beams": [{"name": "rod", "from": [0.15, 0, 0], "to": [0.45, 0, 0], "elements": )" + n +
                           R"(, "E": )" + num(young) + R"(, "G": )" + num(young / 2.6) +
                           R"(, "density": 7870, "section": {"area": )" + num(area) + R"(, "Iy": )" +
                           num(inertia) + R"(, "Iz": )" + num(inertia) + R"(, "J": )" +
                           num(2 * inertia) + R"(}}],
    "joints": [{"name": "shaft", "type": "revolute", "body1": "ground", "body2": "crank", "point2": [-0.075, 0, 0],
                "motor": {"type": "velocity", "function": {"type": "table", "t": [)" + t_list + R"(], "value": [)" + w_list + R"(]}}},
               {"name": "crank_pin", "type": "revolute", "body1": "crank", "body2": "rod.0", "point1": [0.075, 0, 0]},
               {"name": "wrist_pin", "type": "revolute", "body1": "rod.)" + n + R"(", "body2": "slider"},
               {"name": "guide", "type": "prismatic", "body1": "ground", "body2": "slider", "point1": [0.45, 0, 0],
                "axis1": [1, 0, 0]}],
    "simulation": {"t_end": 0.15, "output_interval": 0.001}})";
  const Model m = read_model_text(text, "elastic_slider_crank.json");
  MultibodySystem sys(m);
  const RunOptions o = options_from_model(m);
  REQUIRE(o.method == Method::tirk);  // the default for a model with beams
  test::MemorySink sink;
  run_simulation(sys, o, &sink);
  const StateLayout& lay = sys.layout();
  const Eigen::Index slider = 1, first = 2, mid = first + elements / 2, last = first + elements;
  CrankRun out;
  for (std::size_t k = 0; k < sink.times.size(); ++k) {
    if (sink.times[k] < 0.1 - 1e-12) continue;
    const Eigen::VectorXd& y = sink.states[k];
    const auto at = [&](Eigen::Index b) { return Eigen::Vector2d(y.segment<2>(lay.position(b))); };
    const Eigen::Vector2d pin = at(first), chord = at(last) - pin, arm = at(mid) - pin;
    out.deflection = std::max(out.deflection, std::abs(chord.x() * arm.y() - chord.y() * arm.x()) / chord.norm());
    const double theta = std::atan2(pin.y(), pin.x());
    const double rigid = r * std::cos(theta) + std::sqrt(l * l - std::pow(r * std::sin(theta), 2));
    out.slider_gap = std::max(out.slider_gap, std::abs(at(slider).x() - rigid));
  }
  return out;
}

}  // namespace

TEST_CASE("a slider-crank with an elastic rod: its midpoint deflection converges in elements and the rigid rod's motion is "
          "its limit as the rod stiffens",
          "[analysis][beams]") {
  constexpr double steel = 2.1e11;
  const CrankRun e4 = elastic_slider_crank(4, steel), e8 = elastic_slider_crank(8, steel), e16 = elastic_slider_crank(16, steel);
  INFO("midpoint deflection, 4/8/16 elements: " << e4.deflection << ", " << e8.deflection << ", " << e16.deflection << " m");
  CHECK(e16.deflection > 1e-3);  // millimetres: the rod really bends at 150 rad/s
  CHECK(std::abs(e16.deflection - e8.deflection) < 0.5 * std::abs(e8.deflection - e4.deflection));
  // Second order from 8 elements on (16 -> 32 elements: a quarter of 8 -> 16, measured with
  // a finer output grid); from 4 the ratio of the differences is about 0.4.
  CHECK(std::abs(e16.deflection - e8.deflection) < 0.03 * e16.deflection);
  // Ten and a hundred times stiffer: the deflection and the slider's gap from the rigid
  // rod's kinematics shrink with 1/E.
  const CrankRun stiff = elastic_slider_crank(8, 10 * steel), stiffer = elastic_slider_crank(8, 100 * steel);
  INFO("deflection " << e8.deflection << ", " << stiff.deflection << ", " << stiffer.deflection << " m; slider gap "
                     << e8.slider_gap << ", " << stiff.slider_gap << ", " << stiffer.slider_gap << " m");
  CHECK(stiff.deflection / e8.deflection == Approx(0.1).margin(0.02));
  CHECK(stiffer.deflection / stiff.deflection == Approx(0.1).margin(0.02));
  CHECK(e8.slider_gap < 1e-3 * 0.3);
  CHECK(stiff.slider_gap < 0.2 * e8.slider_gap);
  CHECK(stiffer.slider_gap < 0.2 * stiff.slider_gap);
}
