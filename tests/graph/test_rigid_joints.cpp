// Rigid and compliant kinematic joints in MultibodySystem against exact solutions and
// conservation laws.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "constraint_rows.hpp"
#include "mbsflow/error.hpp"
#include "test_support.hpp"

using namespace mbsflow;
using test::make_body;

namespace {

constexpr double g = 9.81;
const Vec6 rod_inertia{1e-4, 1.0 / 12.0, 1.0 / 12.0, 0, 0, 0};  // 1 kg, 1 m, along body x

// A uniform rod of 1 m and 1 kg pinned at its left end to the ground origin, horizontal.
Model pinned_rod(double gravity) {
  Model m;
  m.gravity = {0, -gravity, 0};
  m.bodies.push_back(make_body("rod", 1.0, rod_inertia, {0.5, 0, 0}));
  m.joints.push_back(test::make_joint(JointType::revolute, ground, 0, {0, 0, 0}, {-0.5, 0, 0}));
  m.joints[0].frame2 = rest_frame2(m, m.joints[0]);
  return m;
}

double rod_angle(const MultibodySystem& sys, const Eigen::VectorXd& y) {
  const Eigen::Vector3d c = y.segment<3>(sys.layout().position(0));
  return std::atan2(c[1], c[0]);
}

}  // namespace

TEST_CASE("a rigid revolute pendulum follows its reduced equation and conserves energy", "[joints]") {
  const Model m = pinned_rod(g);
  MultibodySystem sys(m);
  const double e0 = sys.energy(0, sys.initial_state()).total();
  double worst_violation = 0.0, worst_energy = 0.0;
  const Eigen::VectorXd y = test::integrate_rk4(sys, 2.0, 4000, [&](double t, const Eigen::VectorXd& s) {
    worst_violation = std::max(worst_violation, sys.constraint_violation(t, s));
    worst_energy = std::max(worst_energy, std::abs(sys.energy(t, s).total() - e0));
  });
  // I_pivot theta'' = -m g (L/2) cos(theta), I_pivot = m L^2 / 3 (the rod's axial inertia plays no part).
  const double exact = test::reduced_rk4([](double th) { return -1.5 * g * std::cos(th); }, 0.0, 0.0, {2.0}, 1e-5)[0];
  CHECK(rod_angle(sys, y) == Approx(exact).margin(1e-7));
  CHECK(worst_violation < 1e-10);
  CHECK(worst_energy < 1e-6);
}

TEST_CASE("the reaction of a released pendulum's pivot is a quarter of its weight", "[joints]") {
  MultibodySystem sys(pinned_rod(g));
  Eigen::VectorXd w;
  sys.joint_wrenches(0.0, sys.initial_state(), w);
  // The centre falls at 3g/4, so the pivot carries m g - m 3g/4 upwards.
  CHECK(w[0] == Approx(0.0).margin(1e-9));
  CHECK(w[1] == Approx(g / 4).epsilon(1e-9));
  CHECK(w.segment<3>(3).norm() < 1e-9);  // a revolute joint's reaction about its point: no torque about z
}

TEST_CASE("motors prescribe a joint's position, velocity or effort", "[joints]") {
  const double inertia = 1.0 / 3.0;  // the rod about its pivot
  SECTION("effort: a constant torque spins the rod up uniformly") {
    Model m = pinned_rod(0.0);
    m.joints[0].motor.edit() = {JointMotor::Kind::effort, TimeFunction::constant(0.2)};
    MultibodySystem sys(m);
    const Eigen::VectorXd y = test::integrate_rk4(sys, 1.0, 1000);
    CHECK(rod_angle(sys, y) == Approx(0.5 * 0.2 / inertia).epsilon(1e-9));
  }
  SECTION("position: the angle is the function and the effort is I f''") {
    Model m = pinned_rod(0.0);
    const TimeFunction f = TimeFunction::harmonic(0.4, 0.5);
    m.joints[0].motor.edit() = {JointMotor::Kind::position, f};
    MultibodySystem sys(m);
    double worst = 0.0;
    const Eigen::VectorXd y = test::integrate_rk4(sys, 1.3, 2600, [&](double t, const Eigen::VectorXd& s) {
      worst = std::max(worst, std::abs(rod_angle(sys, s) - evaluate(f, t).value));
    });
    CHECK(worst < 1e-9);
    Eigen::VectorXd w;
    sys.joint_wrenches(1.3, y, w);
    CHECK(sys.motor_efforts()[0] == Approx(inertia * evaluate(f, 1.3).accel).epsilon(1e-6));
  }
  SECTION("velocity: the rate is the function") {
    Model m = pinned_rod(g);
    m.joints[0].motor.edit() = {JointMotor::Kind::velocity, TimeFunction::constant(2.0)};
    MultibodySystem sys(m);
    const Eigen::VectorXd y = test::integrate_rk4(sys, 1.0, 1000);
    CHECK(rod_angle(sys, y) == Approx(2.0).epsilon(1e-9));
  }
  SECTION("prismatic effort: a constant force accelerates the slider uniformly") {
    Model m;
    m.bodies.push_back(make_body("slider", 2.0, {1, 1, 1, 0, 0, 0}));
    Joint j = test::make_joint(JointType::prismatic, ground, 0, {0, 0, 0}, {0, 0, 0});
    j.frame1 = {std::sqrt(0.5), 0, std::sqrt(0.5), 0};  // axis z along world x
    j.frame2 = rest_frame2(m, j);
    j.motor.edit() = {JointMotor::Kind::effort, TimeFunction::constant(3.0)};
    m.joints.push_back(j);
    m.loads.push_back({0, {0, 5, 0}, {0, 0, 1}, {}, false, TimeFunction::constant(1.0)});  // the joint holds these
    MultibodySystem sys(m);
    const Eigen::VectorXd y = test::integrate_rk4(sys, 1.0, 100);
    CHECK(y[0] == Approx(0.5 * 3.0 / 2.0).epsilon(1e-12));
    CHECK(std::abs(y[1]) < 1e-12);
    CHECK(y.segment<3>(sys.layout().angular_velocity(0)).norm() < 1e-12);
  }
}

TEST_CASE("a limit stop holds a driven joint at its limit plus effort over stiffness", "[joints]") {
  Model m = pinned_rod(0.0);
  m.joints[0].motor.edit() = {JointMotor::Kind::effort, TimeFunction::constant(1.0)};
  m.joints[0].limits.edit() = {true, -0.5, 0.5, 1000.0, 30.0};
  MultibodySystem sys(m);
  const Eigen::VectorXd y = test::integrate_rk4(sys, 8.0, 16000);
  CHECK(rod_angle(sys, y) == Approx(0.5 + 1.0 / 1000.0).epsilon(1e-6));
}

TEST_CASE("every joint type conserves energy and keeps its constraints in a swinging chain", "[joints]") {
  for (JointType type : {JointType::spherical, JointType::revolute, JointType::prismatic, JointType::cylindrical,
                         JointType::universal, JointType::planar, JointType::fixed, JointType::distance,
                         JointType::screw}) {
    CAPTURE(joint_type_name(type));
    Model m;
    m.gravity = {0, -g, 0};
    m.bodies.push_back(make_body("a", 1.0, {0.05, 0.08, 0.1, 0.01, 0, 0}, {0.5, 0, 0}));
    m.bodies.push_back(make_body("b", 2.0, {0.1, 0.07, 0.12, 0, 0.01, 0}, {1.5, 0.1, 0}));
    m.bodies[0].velocity = {0.3, -0.5, 0.4};
    m.bodies[0].angular_velocity = {0.5, -0.3, 1.0};
    m.bodies[1].velocity = {-0.2, 0.3, 0.1};
    m.bodies[1].angular_velocity = {-0.4, 0.8, 0.2};
    // A spherical pivot to ground keeps the chain near the origin; the joint under test
    // joins the two bodies.
    m.joints.push_back(test::make_joint(JointType::spherical, ground, 0, {0, 0, 0}, {-0.5, 0, 0}));
    Joint j = test::make_joint(type, 0, 1, {0.5, 0, 0}, type == JointType::distance ? Vec3{0.4, -0.1, 0} : Vec3{-0.5, -0.1, 0});
    j.frame1 = {std::cos(0.3), std::sin(0.3), 0, 0};
    if (type == JointType::universal) j.frame2 = {std::cos(0.3 + std::numbers::pi / 4), std::sin(0.3 + std::numbers::pi / 4), 0, 0};
    else j.frame2 = rest_frame2(m, j);
    j.rest_length = 0.9;
    m.joints.push_back(j);
    if (type == JointType::universal) m.joints.back().frame2 = [&] {
      // z of frame2 perpendicular to z of frame1: turn frame1 by 90 degrees about x.
      Joint u = j;
      u.frame1 = {std::cos(0.3 + std::numbers::pi / 4), std::sin(0.3 + std::numbers::pi / 4), 0, 0};
      return rest_frame2(m, u);
    }();
    MultibodySystem sys(m);
    const Eigen::VectorXd y0 = sys.initial_state();  // projects the velocities onto the joints
    const double e0 = sys.energy(0, y0).total();
    double worst_violation = 0.0, worst_energy = 0.0;
    test::integrate_rk4(sys, 1.0, 2000, [&](double t, const Eigen::VectorXd& s) {
      worst_violation = std::max(worst_violation, sys.constraint_violation(t, s));
      worst_energy = std::max(worst_energy, std::abs(sys.energy(t, s).total() - e0));
    });
    CHECK(worst_violation < 1e-10);
    CHECK(worst_energy < 1e-6 * std::max(1.0, std::abs(e0)));
  }
}

TEST_CASE("a nut on a vertical screw falls at g c^2 m / (m c^2 + I) over whole turns", "[joints]") {
  // One coordinate: the turn theta about z, the advance z = c theta with c = pitch / (2 pi).
  // (m c^2 + I_zz) theta'' = -m g c: the nut falls with constant acceleration and turns
  // five times in 2 s.
  const double mass = 1.0, izz = 1e-3, pitch = 0.01, c = pitch / (2.0 * std::numbers::pi);
  Model m;
  m.gravity = {0, 0, -g};
  m.bodies.push_back(make_body("nut", mass, {2e-3, 2e-3, izz, 0, 0, 0}));
  Joint screw = test::make_joint(JointType::screw, ground, 0, {0, 0, 0}, {0, 0, 0});
  screw.rest_length = pitch;
  m.joints.push_back(screw);
  MultibodySystem sys(m);
  const double e0 = sys.energy(0, sys.initial_state()).total();
  double worst_violation = 0.0, worst_energy = 0.0;
  const double t_end = 2.0;
  const Eigen::VectorXd y = test::integrate_rk4(sys, t_end, 4000, [&](double t, const Eigen::VectorXd& s) {
    worst_violation = std::max(worst_violation, sys.constraint_violation(t, s));
    worst_energy = std::max(worst_energy, std::abs(sys.energy(t, s).total() - e0));
  });
  const double fall = 0.5 * g * mass * c * c / (mass * c * c + izz) * t_end * t_end;
  const Eigen::Vector3d r = y.segment<3>(sys.layout().position(0));
  CHECK(r[2] == Approx(-fall).epsilon(1e-9));
  CHECK(std::hypot(r[0], r[1]) < 1e-12);
  const Eigen::Vector4d q = y.segment<4>(sys.layout().orientation(0));
  const double turned = 2.0 * std::atan2(q[3], q[0]);  // about z
  CHECK(fall / c > 4 * 2.0 * std::numbers::pi);  // past +-pi several times
  CHECK(std::remainder(turned + fall / c, 2.0 * std::numbers::pi) == Approx(0.0).margin(1e-7));
  CHECK(worst_violation < 1e-10);
  CHECK(worst_energy < 1e-9);
}

TEST_CASE("a compliant joint in the seed's form conserves energy and approaches the rigid one", "[joints]") {
  Model rigid = pinned_rod(g), soft = rigid;
  soft.joints[0].rigid = false;
  set_bushing_from_frequency(soft, soft.joints[0], 400.0, 0.0);
  MultibodySystem a(rigid), b(soft);
  const double e0 = b.energy(0, b.initial_state()).total();
  double worst_energy = 0.0;
  const Eigen::VectorXd yb = test::integrate_rk4(b, 1.0, 20000, [&](double t, const Eigen::VectorXd& s) {
    worst_energy = std::max(worst_energy, std::abs(b.energy(t, s).total() - e0));
  });
  const Eigen::VectorXd ya = test::integrate_rk4(a, 1.0, 2000);
  CHECK(worst_energy < 1e-6);
  CHECK(rod_angle(b, yb) == Approx(rod_angle(a, ya)).margin(2e-3));
}

TEST_CASE("redundant rigid joints are solved, contradictory ones are refused", "[joints]") {
  SECTION("two fixed joints between the same bodies: the pair falls freely as one") {
    Model m;
    m.gravity = {0, -g, 0};
    m.bodies.push_back(make_body("a", 1.0, {1, 1, 1, 0, 0, 0}));
    m.bodies.push_back(make_body("b", 3.0, {1, 2, 2, 0, 0, 0}, {1, 0, 0}));
    for (int k = 0; k < 2; ++k) m.joints.push_back(test::make_joint(JointType::fixed, 0, 1, {0.5, 0, 0}, {-0.5, 0, 0}));
    m.joints[1].name = "again";
    MultibodySystem sys(m);
    const Eigen::VectorXd y = test::integrate_rk4(sys, 1.0, 100);
    CHECK(y[1] == Approx(-0.5 * g).epsilon(1e-10));
    CHECK(y[4] == Approx(-0.5 * g).epsilon(1e-10));
    CHECK(y[3] == Approx(1.0).epsilon(1e-12));
  }
  SECTION("two rods to one body from pivots too far apart") {
    Model m;
    m.bodies.push_back(make_body("mass", 1.0, {1, 1, 1, 0, 0, 0}, {0, 1, 0}));
    m.joints.push_back(test::make_joint(JointType::distance, ground, 0, {-1, 0, 0}, {0, 0, 0}));
    m.joints.push_back(test::make_joint(JointType::distance, ground, 0, {5, 0, 0}, {0, 0, 0}));
    m.joints[0].rest_length = 1.0;
    m.joints[1].rest_length = 1.0;
    m.joints[1].name = "far";
    MultibodySystem sys(m);
    CHECK_THROWS_AS(sys.initial_state(), InputError);
  }
}
