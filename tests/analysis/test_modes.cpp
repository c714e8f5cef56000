// Modes, equilibrium and frequency response against exact answers: a body on a bushing,
// the natural-frequency form, a chain of springs, single and double pendulums on rigid
// revolute joints, a damped oscillator's frequency response; the dense and the sparse
// solver against each other.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "mbsflow/analysis/equilibrium.hpp"
#include "mbsflow/analysis/frequency_response.hpp"
#include "mbsflow/analysis/modes.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

constexpr double pi = std::numbers::pi;

struct Linearised {
  Model model;
  std::unique_ptr<MultibodySystem> sys;
  LinearModel lm;
};

// The model of `json`, linearised at its static equilibrium (or its initial state).
Linearised linearised(const std::string& json, bool equilibrium = true) {
  Linearised out;
  out.model = read_model_text(json, "test model");
  out.sys = std::make_unique<MultibodySystem>(out.model);
  Eigen::VectorXd y = out.sys->initial_state();
  if (equilibrium) y = find_equilibrium(*out.sys, 0.0, y).state;
  out.lm = linearize(*out.sys, 0.0, y);
  return out;
}

Modes modes_of(const LinearModel& lm, int count, bool damped, ModeSolver solver = ModeSolver::automatic) {
  ModeOptions o;
  o.count = count;
  o.damped = damped;
  o.solver = solver;
  return compute_modes(lm, o);
}

const char* bushing_body = R"({"name": "mount", "gravity": [0, 0, 0],
  "bodies": [{"name": "block", "mass": 2.0, "inertia": [0.3, 0.5, 0.7], "position": [0, 0, 0]}],
  "joints": [{"name": "pad", "type": "bushing", "body1": "ground", "body2": "block", "point1": [0, 0, 0], "point2": [0, 0, 0],
              %s}]})";

std::string with(const char* format, const std::string& fields) {
  std::string s = format;
  return s.replace(s.find("%s"), 2, fields);
}

}  // namespace

TEST_CASE("a body on a bushing vibrates at sqrt(k/m) along and sqrt(kr/I) about each axis", "[analysis][modes]") {
  const Linearised l = linearised(with(bushing_body, R"("stiffness": [800, 1800, 3200, 30, 80, 140])"), false);
  const Modes m = modes_of(l.lm, 10, false);
  REQUIRE(m.frequency.size() == 6);  // all there are
  std::vector<double> expected = {std::sqrt(800 / 2.0), std::sqrt(1800 / 2.0), std::sqrt(3200 / 2.0),
                                  std::sqrt(30 / 0.3),  std::sqrt(80 / 0.5),    std::sqrt(140 / 0.7)};
  std::sort(expected.begin(), expected.end());
  for (std::size_t j = 0; j < 6; ++j) {
    CHECK(m.frequency[j] == Approx(expected[j] / (2 * pi)).epsilon(1e-10));
    CHECK(m.damping_ratio[j] == Approx(0.0).margin(1e-12));
    CHECK(m.residual[j] < 1e-12);
    CHECK(!m.rigid_body[j]);
    CHECK(m.kinetic_share(0, static_cast<Eigen::Index>(j)) == Approx(1.0));
  }
  // Mass-normalised: x^H M x = 1.
  const Eigen::VectorXcd x = m.shape.col(0);
  CHECK(std::abs((x.adjoint() * (l.lm.M * x))(0)) == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("bodies on bushings in the natural-frequency form: every mode at Omega with damping ratio mu", "[analysis][modes]") {
  const double omega = 40.0, mu = 0.05;
  std::string bodies, joints;
  for (int i = 0; i < 4; ++i) {
    const std::string b = "b" + std::to_string(i), at = std::to_string(2.0 * i);
    bodies += std::string(i ? "," : "") + R"({"name": ")" + b + R"(", "mass": )" + std::to_string(1.0 + i) +
              R"(, "inertia": [0.3, 0.5, 0.7], "position": [)" + at + ", 0, 0]}";
    joints += std::string(i ? "," : "") + R"({"name": "p)" + b + R"(", "type": "bushing", "body1": "ground", "body2": ")" + b +
              R"(", "point1": [)" + at + R"(, 0, 0], "point2": [0, 0, 0], "frequency": 40, "damping_ratio": 0.05})";
  }
  const Linearised l = linearised(R"({"name": "mounts", "gravity": [0, 0, 0], "bodies": [)" + bodies + R"(], "joints": [)" + joints +
                                  "]}", false);
  for (ModeSolver solver : {ModeSolver::dense, ModeSolver::sparse}) {
    INFO((solver == ModeSolver::dense ? "dense" : "sparse"));
    const Modes m = modes_of(l.lm, 6, true, solver);
    REQUIRE(m.frequency.size() == 6);
    CHECK(m.solver.find(solver == ModeSolver::dense ? "dense" : "sparse") == 0);
    for (std::size_t j = 0; j < 6; ++j) {
      CHECK(std::abs(m.eigenvalue[j]) == Approx(omega).epsilon(1e-9));
      CHECK(m.damping_ratio[j] == Approx(mu).epsilon(1e-9));
      CHECK(m.eigenvalue[j].real() == Approx(-mu * omega).epsilon(1e-9));
      CHECK(m.residual[j] < 1e-10);
    }
  }
}

TEST_CASE("a chain of masses and springs, fixed at one end: the closed-form frequencies", "[analysis][modes]") {
  // n masses m on springs k along x; the j-th frequency 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1))).
  const int n = 8;
  const double k = 1000.0, mass = 0.5;
  std::string bodies, joints;
  for (int i = 0; i < n; ++i) {
    bodies += std::string(i ? "," : "") + R"({"name": "m)" + std::to_string(i) + R"(", "mass": 0.5, "inertia": [0.01, 0.01, 0.01], "position": [)" +
              std::to_string(i + 1) + ", 0, 0]}";
    joints += std::string(i ? "," : "") + R"({"name": "s)" + std::to_string(i) + R"(", "type": "spring", "body1": ")" +
              (i ? "m" + std::to_string(i - 1) : std::string("ground")) + R"(", "body2": "m)" + std::to_string(i) +
              R"(", "point1": [)" + (i ? "0" : "0") + R"(, 0, 0], "point2": [0, 0, 0], "stiffness": 1000})";
  }
  const Linearised l = linearised(R"({"name": "springs", "gravity": [0, 0, 0], "bodies": [)" + bodies + R"(], "joints": [)" +
                                  joints + "]}", false);
  const Modes m = modes_of(l.lm, 6 * n, false);
  std::vector<double> vibrating;
  int rigid = 0;
  for (std::size_t j = 0; j < m.frequency.size(); ++j) {
    if (m.rigid_body[j]) ++rigid;
    else vibrating.push_back(m.frequency[j]);
  }
  CHECK(rigid == 5 * n);  // sideways and turning: no stiffness without tension
  REQUIRE(vibrating.size() == static_cast<std::size_t>(n));
  for (int j = 1; j <= n; ++j)
    CHECK(vibrating[static_cast<std::size_t>(j - 1)] ==
          Approx(2.0 * std::sqrt(k / mass) * std::sin((2 * j - 1) * pi / (2.0 * (2 * n + 1))) / (2 * pi)).epsilon(1e-9));
}

TEST_CASE("a pendulum on a rigid revolute released off its equilibrium: found hanging, one mode at sqrt(m g L / I_pivot)",
          "[analysis][modes][equilibrium]") {
  // Bob of 1 kg at 1.2 m, 60 degrees off the vertical; inertia 0.02 about z.
  const double L = 1.2, m = 1.0, izz = 0.02, g = 9.81;
  const double x = L * std::sin(pi / 3), y = -L * std::cos(pi / 3);
  char json[1024];
  std::snprintf(json, sizeof json, R"({"name": "pendulum", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.02, 0.02, 0.02], "position": [%.17g, %.17g, 0]}],
    "joints": [{"name": "pivot", "type": "revolute", "body1": "ground", "body2": "bob", "point1": [0, 0, 0],
                "point2": [%.17g, %.17g, 0], "axis1": [0, 0, 1]}]})", x, y, -x, -y);
  Model model = read_model_text(json, "pendulum");
  MultibodySystem sys(model);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  const StateLayout& l = sys.layout();
  CHECK(e.state[l.position(0)] == Approx(0.0).margin(1e-9));
  CHECK(e.state[l.position(0) + 1] == Approx(-L).epsilon(1e-9));
  CHECK(e.residual < 1e-8);
  const LinearModel lm = linearize(sys, 0.0, e.state);
  CHECK(lm.C.rows() == 5);
  const Modes modes = modes_of(lm, 10, true);
  REQUIRE(modes.frequency.size() == 1);  // no constraint direction shows up as a mode
  CHECK(modes.frequency[0] == Approx(std::sqrt(m * g * L / (izz + m * L * L)) / (2 * pi)).epsilon(1e-9));
  CHECK(modes.residual[0] < 1e-10);
  // Sparse, through the augmented pencil: the same.
  const Modes sparse = modes_of(lm, 1, true, ModeSolver::sparse);
  REQUIRE(sparse.frequency.size() >= 1);
  CHECK(sparse.frequency[0] == Approx(modes.frequency[0]).epsilon(1e-8));
}

TEST_CASE("a double pendulum of point-like bobs: frequencies sqrt(g/L (2 -+ sqrt 2))", "[analysis][modes][equilibrium]") {
  // Released level (both rods horizontal); equal bobs, rods L.
  const char* json = R"({"name": "double", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "upper", "mass": 1.0, "inertia": [1e-7, 1e-7, 1e-7], "position": [1, 0, 0]},
               {"name": "lower", "mass": 1.0, "inertia": [1e-7, 1e-7, 1e-7], "position": [2, 0, 0]}],
    "joints": [{"name": "shoulder", "type": "revolute", "body1": "ground", "body2": "upper", "point1": [0, 0, 0],
                "point2": [-1, 0, 0], "axis1": [0, 0, 1]},
               {"name": "elbow", "type": "revolute", "body1": "upper", "body2": "lower", "point1": [0, 0, 0],
                "point2": [-1, 0, 0], "axis1": [0, 0, 1]}]})";
  const Linearised l = linearised(json);
  const Modes m = modes_of(l.lm, 10, false);
  REQUIRE(m.frequency.size() == 2);
  CHECK(m.frequency[0] == Approx(std::sqrt(9.81 * (2 - std::sqrt(2.0))) / (2 * pi)).epsilon(1e-5));
  CHECK(m.frequency[1] == Approx(std::sqrt(9.81 * (2 + std::sqrt(2.0))) / (2 * pi)).epsilon(1e-5));
}

TEST_CASE("a free body has six rigid-body modes, reported as such", "[analysis][modes]") {
  const Linearised l = linearised(R"({"name": "free", "gravity": [0, 0, 0],
    "bodies": [{"name": "b", "mass": 3.0, "inertia": [0.1, 0.2, 0.3], "position": [0, 0, 0]}], "joints": []})", false);
  const Modes m = modes_of(l.lm, 10, true);
  REQUIRE(m.frequency.size() == 6);
  for (std::size_t j = 0; j < 6; ++j) {
    CHECK(m.rigid_body[j]);
    CHECK(m.frequency[j] == 0.0);
  }
}

// A chain of n links of 1 kg along x with the given inertia, each joined to the one before
// by `joint` (JSON fields after the name and bodies), the first to the ground unless
// `floating`; no gravity where floating.
std::string link_chain(int n, const std::string& inertia, const std::string& joint, bool floating) {
  std::string bodies, joints;
  for (int i = 0; i < n; ++i) {
    bodies += std::string(i ? "," : "") + R"({"name": "l)" + std::to_string(i) +
              R"(", "mass": 1.0, "inertia": )" + inertia + R"(, "position": [)" + std::to_string(0.5 * i) + ", 0, 0]}";
    if (floating && i == 0) continue;
    joints += std::string(joints.empty() ? "" : ",") + R"({"name": "j)" + std::to_string(i) + R"(", "body1": ")" +
              (i ? "l" + std::to_string(i - 1) : std::string("ground")) + R"(", "body2": "l)" + std::to_string(i) +
              R"(", "point1": [)" + (i ? "0.25" : "-0.25") + R"(, 0, 0], "point2": [-0.25, 0, 0], )" + joint + "}";
  }
  return R"({"name": "chain", "gravity": [0, )" + std::string(floating ? "0" : "-9.81") + R"(, 0], "bodies": [)" + bodies +
         R"(], "joints": [)" + joints + "]}";
}

const std::string damped_bushing =
    R"("type": "bushing", "stiffness": [4e4, 3e4, 3e4, 50, 80, 80], "damping": [5, 5, 5, 0.01, 0.01, 0.01])";

// A hanging chain of n bodies on damped bushings.
std::string bushing_chain(int n) { return link_chain(n, "[0.01, 0.02, 0.02]", damped_bushing, false); }

TEST_CASE("the stiffness is minus the static residual's derivative at the equilibrium, and K alone where no damping is asked",
          "[analysis][modes]") {
  const Linearised l = linearised(bushing_chain(12));
  const LinearModel stiff = linearize(*l.sys, 0.0, l.lm.state, nullptr, false);
  CHECK(stiff.D.nonZeros() == 0);
  CHECK(stiff.D.rows() == l.lm.size());
  CHECK((stiff.K - l.lm.K).norm() == 0.0);
  CHECK(l.lm.D.norm() > 0.0);
  // Central differences of the residual (M a at rest) along each coordinate: at an
  // equilibrium (a = 0) its derivative is -K, the mass matrix's own change times a vanishing.
  const StateLayout& layout = l.sys->layout();
  const Eigen::Index n = l.lm.size();
  const double h = 1e-6;
  Eigen::MatrixXd differenced(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd plus = l.lm.state, minus = l.lm.state, step = Eigen::VectorXd::Zero(n);
    step[j] = h;
    apply_tangent_step(layout, l.lm.coords, step, plus);
    apply_tangent_step(layout, l.lm.coords, -step, minus);
    differenced.col(j) = -(static_residual(*l.sys, 0.0, plus, l.lm.coords) - static_residual(*l.sys, 0.0, minus, l.lm.coords)) / (2.0 * h);
  }
  const Eigen::MatrixXd k = l.lm.K;
  CHECK((k - differenced).cwiseAbs().maxCoeff() < 1e-6 * k.cwiseAbs().maxCoeff());
}

TEST_CASE("the sparse shift-invert solver finds the dense solver's lowest modes of a chain of bushings", "[analysis][modes]") {
  const Linearised l = linearised(bushing_chain(60));
  const Modes dense = modes_of(l.lm, 8, true, ModeSolver::dense), sparse = modes_of(l.lm, 8, true, ModeSolver::sparse);
  REQUIRE(dense.frequency.size() == 8);
  REQUIRE(sparse.frequency.size() >= 8);
  for (std::size_t j = 0; j < 8; ++j) {
    CHECK(sparse.frequency[j] == Approx(dense.frequency[j]).epsilon(1e-8));
    CHECK(std::abs(sparse.damping_ratio[j] - dense.damping_ratio[j]) < 1e-9);  // Re lambda to 1e-9 |lambda|
    CHECK(sparse.residual[j] < 1e-8);
    CHECK(dense.residual[j] < 1e-8);
  }
}

TEST_CASE("the sparse undamped modes are the dense solver's: Lanczos on bushings and rigid joints, Arnoldi with rigid-body motions",
          "[analysis][modes]") {
  struct Case {
    const char* name;
    std::string json;
    int count, rigid;
    const char* solver;
    double tolerance;
  };
  const std::vector<Case> cases = {
      {"a hanging chain of 60 bushings", bushing_chain(60), 8, 0, "Lanczos", 1e-8},
      {"a hanging chain of 60 links on revolute joints (augmented matrix)",
       link_chain(60, "[0.01, 0.02, 0.03]", R"("type": "revolute", "axis1": [0, 0, 1])", false), 4, 0, "Lanczos", 1e-8},
      // The Arnoldi's rounding at the rigid-body motions' images (1 / |sigma|) leaves the
      // vibrations a few times 1e-8 off.
      {"a floating chain of 20 bushed links (six rigid-body motions)", link_chain(20, "[0.01, 0.02, 0.03]", damped_bushing, true), 10, 6, "Arnoldi", 1e-7},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const Linearised l = linearised(c.json, c.rigid == 0);
    const Modes dense = modes_of(l.lm, c.count, false, ModeSolver::dense), sparse = modes_of(l.lm, c.count, false, ModeSolver::sparse);
    CHECK(sparse.solver.find(c.solver) != std::string::npos);
    REQUIRE(dense.frequency.size() == static_cast<std::size_t>(c.count));
    REQUIRE(sparse.frequency.size() == static_cast<std::size_t>(c.count));
    for (std::size_t j = 0; j < static_cast<std::size_t>(c.count); ++j) {
      INFO("mode " << j);
      CHECK(sparse.rigid_body[j] == (static_cast<int>(j) < c.rigid));
      CHECK(dense.rigid_body[j] == sparse.rigid_body[j]);
      if (sparse.rigid_body[j]) continue;
      CHECK(sparse.frequency[j] == Approx(dense.frequency[j]).epsilon(c.tolerance));
      CHECK(std::abs(sparse.damping_ratio[j]) < c.tolerance);
      CHECK(sparse.residual[j] < c.tolerance);
    }
  }
}

TEST_CASE("a damped oscillator's frequency response is 1 / (k - m w^2 + i c w)", "[analysis][frf]") {
  const Linearised l = linearised(with(bushing_body, R"("stiffness": [800, 1800, 3200, 30, 80, 140], "damping": [4, 1, 1, 0.1, 0.1, 0.1])"), false);
  const std::vector<Channel> in = {parse_channel(l.model, "block:fx", true)};
  const std::vector<Channel> out = {parse_channel(l.model, "block:x", false), parse_channel(l.model, "block:vx", false),
                                    parse_channel(l.model, "block:ax", false), parse_channel(l.model, "block:y", false)};
  const std::vector<double> hz = {0.5, 3.0, std::sqrt(400.0) / (2 * pi), 10.0, 80.0};
  const FrequencyResponse r = frequency_response(l.lm, in, out, hz);
  for (std::size_t k = 0; k < hz.size(); ++k) {
    const double w = 2 * pi * hz[k];
    const std::complex<double> h = 1.0 / std::complex<double>(800.0 - 2.0 * w * w, 4.0 * w);
    CHECK(std::abs(r.h[k](0, 0) - h) < 1e-12 * std::abs(h));
    CHECK(std::abs(r.h[k](1, 0) - std::complex<double>(0, w) * h) < 1e-12 * std::abs(h) * w);
    CHECK(std::abs(r.h[k](2, 0) + w * w * h) < 1e-12 * std::abs(h) * w * w);
    CHECK(std::abs(r.h[k](3, 0)) < 1e-14);  // no coupling to y
  }
  CHECK_THROWS_WITH(parse_channel(l.model, "block:fq", true), Catch::Contains("'fq' is not one of fx, fy, fz, tx, ty, tz"));
  CHECK_THROWS_WITH(parse_channel(l.model, "brick:x", false), Catch::Contains("no body 'brick'"));
  // The state-space model gives the same response: C (i w - A)^-1 B + D.
  const StateSpace s = state_space(l.lm, in, out);
  const double w = 2 * pi * 3.0;
  const Eigen::MatrixXcd a = Eigen::MatrixXd(s.A).cast<std::complex<double>>();
  const Eigen::MatrixXcd g = Eigen::MatrixXd(s.C).cast<std::complex<double>>() *
                                 (std::complex<double>(0, w) * Eigen::MatrixXcd::Identity(a.rows(), a.cols()) - a)
                                     .partialPivLu()
                                     .solve(Eigen::MatrixXd(s.B).cast<std::complex<double>>()) +
                             Eigen::MatrixXd(s.D).cast<std::complex<double>>();
  for (Eigen::Index o = 0; o < 4; ++o) CHECK(std::abs(g(o, 0) - r.h[1](o, 0)) < 1e-10 * (std::abs(r.h[1](o, 0)) + 1e-12));
}

TEST_CASE("an unsupported body under gravity: no equilibrium, and the body named", "[analysis][equilibrium]") {
  Model model = read_model_text(R"({"name": "falling", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "stone", "mass": 1.0, "inertia": [0.1, 0.1, 0.1], "position": [0, 0, 0]}], "joints": []})", "falling");
  MultibodySystem sys(model);
  EquilibriumOptions o;
  o.max_iterations = 20;
  CHECK_THROWS_WITH(find_equilibrium(sys, 0.0, sys.initial_state(), o), Catch::Contains("body 'stone' does not settle"));
}

TEST_CASE("a long chain released level hangs in a few iterations with each joint stretched by the weight below it",
          "[analysis][equilibrium]") {
  // 1000 links of 0.1 m and 1 kg on 1e6 N/m bushings, level at the start: the first Newton
  // steps would turn links by hundreds of radians. Cut to the turn limit with h still
  // growing, the steps follow directions cut a hundredfold (45 iterations); h shrinks to
  // the cut instead (17), and the steps swing the links along arcs (14).
  ChainParams p;
  p.bodies = 1000;
  const Model model = make_chain(p);
  MultibodySystem sys(model);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  INFO(e.iterations << " iterations, residual " << e.residual);
  CHECK(e.iterations <= 16);
  // Joint k carries the weight of links k..n-1: the last link's centre lies n - 1/2 links
  // and the joints' stretch below the pivot (the bending stiffness at the pivot, 1 N m/rad
  // against 9810 N of tension, tilts the top link by 3e-3 rad: 1.6e-4 m sideways).
  double stretch = 0.0;
  for (int k = 0; k < p.bodies; ++k) stretch += (p.bodies - k) * p.mass * 9.81 / p.stiffness;
  const Eigen::Vector3d last = e.state.segment<3>(sys.layout().position(p.bodies - 1));
  CHECK(last.y() == Approx(-(p.bodies - 0.5) * p.link_length - stretch).epsilon(1e-8));
  CHECK(std::abs(last.x()) < 1e-3);
  CHECK(std::abs(last.z()) < 1e-9);
}

TEST_CASE("a body released 1 rad above level swings down to hang: along arcs on a stiff bushing", "[analysis][equilibrium]") {
  // 1 kg at 0.5 m from its pivot, released 1 rad above level. On a 1e5 N/m bushing, steps
  // taken about the centre stretched the bushing by the turn's second-order term (4 000 N
  // from a turn of 0.4 rad), so they stayed near 0.1 rad: 53 iterations; along arcs about
  // the bushing, 18. Newton's step from above level heads for standing upright, which
  // balances the forces as well: the pseudo-time steps must not take it.
  const bool bushing = GENERATE(true, false);
  const std::string joint = bushing ? R"("type": "bushing", "stiffness": [1e5, 1e5, 1e5, 0.1, 0.1, 0.1])"
                                    : R"("type": "revolute", "axis1": [0, 0, 1])";
  const std::string json = R"({"name": "b", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.01, 0.02, 0.02], "position": [0.27015115293406986, 0.42073549240394825, 0],
                "orientation": [0.8775825618903728, 0, 0, 0.479425538604203]}],
    "joints": [{"name": "pin", "body1": "ground", "body2": "bob", "point1": [0, 0, 0], "point2": [-0.5, 0, 0], )" +
                           joint + "}]}";
  Model model = read_model_text(json, "b");
  MultibodySystem sys(model);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state());
  INFO((bushing ? "bushing: " : "revolute: ") << e.iterations << " iterations, residual " << e.residual);
  CHECK(e.iterations <= 25);
  // The pivot carries the weight: the body's point there sits m g / k below it on the
  // bushing (whatever angle its small torsional stiffness leaves the body at), on it on
  // the revolute, and the body hangs below.
  const StateLayout& l = sys.layout();
  const auto q = e.state.segment<4>(l.orientation(0));
  const Eigen::Vector3d held =
      e.state.segment<3>(l.position(0)) + Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized() * Eigen::Vector3d(-0.5, 0, 0);
  CHECK(held.x() == Approx(0.0).margin(1e-12));
  CHECK(held.y() == Approx(bushing ? -9.81 / 1e5 : 0.0).epsilon(1e-9).margin(1e-12));
  CHECK(e.state[l.position(0) + 1] < -0.49);
}

TEST_CASE("the modal frequencies are the peaks of a free vibration's spectrum (a transient run, Fourier-transformed)",
          "[analysis][modes]") {
  // Two masses on springs along x, fixed at one end, the outer one pulled 1 cm and let go;
  // its motion sampled at 500 Hz over 40 s and transformed (Hann window).
  const char* json = R"({"name": "two", "gravity": [0, 0, 0],
    "bodies": [{"name": "a", "mass": 0.5, "inertia": [0.01, 0.01, 0.01], "position": [1, 0, 0]},
               {"name": "b", "mass": 0.5, "inertia": [0.01, 0.01, 0.01], "position": [2.01, 0, 0]}],
    "joints": [{"name": "s0", "type": "spring", "body1": "ground", "body2": "a", "point1": [0, 0, 0], "point2": [0, 0, 0],
                "stiffness": 1000, "rest_length": 1},
               {"name": "s1", "type": "spring", "body1": "a", "body2": "b", "point1": [0, 0, 0], "point2": [0, 0, 0],
                "stiffness": 1000, "rest_length": 1}]})";
  Model model = read_model_text(json, "two");
  MultibodySystem sys(model);
  std::vector<double> x;
  const double t_end = 40.0;
  const long steps = 400000, every = 20;  // h = 1e-4 s, samples at 500 Hz
  long k = 0;
  test::integrate_rk4(sys, t_end, steps, [&](double, const Eigen::VectorXd& y) {
    if (++k % every == 0) x.push_back(y[sys.layout().position(1)] - 2.0);
  });
  const double fs = 500.0;
  const auto n = static_cast<double>(x.size());
  auto spectrum = [&](double f) {  // |sum w(t) x(t) e^{-i 2 pi f t}|
    std::complex<double> s = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double w = 0.5 - 0.5 * std::cos(2 * pi * static_cast<double>(i) / (n - 1));
      s += w * x[i] * std::exp(std::complex<double>(0.0, -2 * pi * f * static_cast<double>(i) / fs));
    }
    return std::abs(s);
  };
  // The two largest local maxima on a 0.005 Hz grid up to 20 Hz.
  std::vector<std::pair<double, double>> peaks;
  double before = spectrum(0.0), here = spectrum(0.005);
  for (double f = 0.01; f < 20.0; f += 0.005) {
    const double after = spectrum(f);
    if (here > before && here > after) peaks.emplace_back(here, f - 0.005);
    before = here;
    here = after;
  }
  std::sort(peaks.rbegin(), peaks.rend());
  REQUIRE(peaks.size() >= 2);
  std::vector<double> seen = {peaks[0].second, peaks[1].second};
  std::sort(seen.begin(), seen.end());
  // About the equilibrium (the springs at rest: no tension, so nothing vibrates sideways).
  Linearised l = linearised(json, true);
  const Modes m = modes_of(l.lm, 12, false);
  std::vector<double> vibrating;
  for (std::size_t j = 0; j < m.frequency.size(); ++j)
    if (m.frequency[j] > 0.1) vibrating.push_back(m.frequency[j]);  // sideways: 1e-5 Hz from the residual tension
  REQUIRE(vibrating.size() == 2);
  // Within the transform's resolution (1 / 40 s = 0.025 Hz; the peak of a Hann window is
  // found to a fraction of it).
  CHECK(std::abs(seen[0] - vibrating[0]) < 0.01);
  CHECK(std::abs(seen[1] - vibrating[1]) < 0.01);
}
