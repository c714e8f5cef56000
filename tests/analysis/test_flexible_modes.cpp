// Small motions of a model with a flexible body (analysis/linearization.hpp): free, its
// modes are the reduced part's (six rigid motions, then the free part's elastic
// frequencies, each with its modal damping) wherever the frame is and however it is
// turned; held at its interface by stiff bushings or rigid joints, the fixed-interface
// modes the reduction kept; its frequency response at an interface node, far below the first mode,
// the full lattice's static deflection (Craig-Bampton is exact for loads at interface
// nodes), through a node body's motion (body_motion) both ways.
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "flexible_part.hpp"
#include "mbsflow/analysis/equilibrium.hpp"
#include "mbsflow/analysis/frequency_response.hpp"
#include "mbsflow/analysis/linearization.hpp"
#include "mbsflow/analysis/modes.hpp"
#include "mbsflow/graph/multibody_system.hpp"

using namespace mbsflow;
using test::bar_part;
using test::flexible_model;

namespace {

// Each of the first `count` nodes of the flexible body held to the ground by a bushing of
// translational stiffness k (the lattice's nodes have no rotation), or by a rigid
// spherical joint where k is 0.
void hold_nodes(Model& m, int count, double k) {
  const FlexibleBody& f = m.flexible.front();
  for (int i = 0; i < count; ++i) {
    Joint j;
    j.name = "hold" + std::to_string(i);
    j.type = k > 0.0 ? JointType::bushing : JointType::spherical;
    j.body1 = ground;
    j.body2 = f.nodes[static_cast<std::size_t>(i)];
    j.point1 = m.bodies[static_cast<std::size_t>(j.body2)].position;
    if (k > 0.0) j.stiffness = {k, k, k, 0.0, 0.0, 0.0};
    m.joints.push_back(j);
  }
}

// The bar reduced at nodes 1-4 with 6 modes, held there (hold_nodes' k): its six lowest
// modes are the fixed-interface ones the reduction kept, to `epsilon`.
void check_fixed_interface_modes(double k, double epsilon) {
  const ReducedPart part = bar_part(6);
  Model m = flexible_model(part);
  hold_nodes(m, 4, k);
  MultibodySystem sys(m);
  const LinearModel lm = linearize(sys, 0.0, sys.initial_state());
  ModeOptions o;
  o.count = 6;
  o.damped = false;
  const Modes modes = compute_modes(lm, o);
  REQUIRE(modes.frequency.size() == 6);
  for (std::size_t i = 0; i < 6; ++i) {
    CHECK_FALSE(modes.rigid_body[i]);
    CHECK(modes.frequency[i] == Approx(part.fixed_frequency[static_cast<Eigen::Index>(i)]).epsilon(epsilon));
  }
}

}  // namespace

TEST_CASE("flexible body, free: its modes are the free part's, with their modal damping, however the frame lies",
          "[analysis][flexible][modes]") {
  const ReducedPart part = bar_part(6);
  const FloatingFrameData& d = part.floating;
  const int ne = d.modes();
  Model m = flexible_model(part);
  const double zeta = 0.02;
  m.flexible.front().damping = 2.0 * zeta * d.omega2.cwiseSqrt();
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()));
  m.bodies[0].orientation = {turned.w(), turned.x(), turned.y(), turned.z()};
  m.bodies[0].position = {0.3, -1.0, 2.0};
  MultibodySystem sys(m);
  const LinearModel lm = linearize(sys, 0.0, sys.initial_state());
  REQUIRE(lm.size() == 6 + ne);
  REQUIRE(lm.coords.bodies == std::vector<int>{0});  // the nodes follow the frame and the modes
  ModeOptions o;
  o.count = 6 + ne;
  const Modes modes = compute_modes(lm, o);
  REQUIRE(modes.frequency.size() == static_cast<std::size_t>(6 + ne));
  for (int i = 0; i < 6; ++i) CHECK(modes.rigid_body[static_cast<std::size_t>(i)]);
  for (int k = 0; k < ne; ++k) {
    const auto j = static_cast<std::size_t>(6 + k);
    CHECK_FALSE(modes.rigid_body[j]);
    CHECK(modes.frequency[j] == Approx(std::sqrt(d.omega2[k]) / (2 * std::numbers::pi)).epsilon(1e-7));
    CHECK(modes.damping_ratio[j] == Approx(zeta).epsilon(1e-6));
    CHECK(modes.residual[j] < 1e-8);
  }
}

TEST_CASE("flexible body held at its interface by stiff bushings: its modes are the fixed-interface ones kept",
          "[analysis][flexible][modes]") {
  // The lattice's springs are about 2e6 N/m: a bushing's compliance changes the result by
  // about 2e6 / k (5e-7 at k = 1e12). The analytic Jacobian has no differences' rounding
  // (forces k h at positions of about 1 m, rounded to 1e-16 m, would add k 1e-16 / h to
  // the stiffness, 5e-5 of the lattice's at k = 1e12), so the stiffer the clamp, the closer
  // until the eigensolver's own rounding, about 1e-16 k / omega^2, takes over near 1e13.
  check_fixed_interface_modes(1e11, 3e-5);
  check_fixed_interface_modes(1e12, 1.5e-6);
}

TEST_CASE("flexible body held at its interface by rigid spherical joints: its modes are the fixed-interface ones kept",
          "[analysis][flexible][joints][modes]") {
  check_fixed_interface_modes(0.0, 1e-6);  // the joints' rows hold exactly
}

TEST_CASE("flexible body: the response at an interface node far below its modes is the lattice's static deflection",
          "[analysis][flexible][modes]") {
  // Reduced at the end x = 0 (held) and the far corner, node 24, where the force acts.
  const ReducedPart part = bar_part(6, {1, 2, 3, 4, 24});
  Model m = flexible_model(part);
  hold_nodes(m, 4, 1e11);  // as above: 1e-5 of the compliance
  MultibodySystem sys(m);
  const LinearModel lm = linearize(sys, 0.0, sys.initial_state());
  // The full lattice held at nodes 1-4 (its first 12 DOFs) under a unit force at node 24.
  const test::SpringLattice lattice = test::bar_lattice();
  const Eigen::Index dofs = lattice.fe.stiffness.rows() - 12;
  const Eigen::LDLT<Eigen::MatrixXd> held(Eigen::MatrixXd(lattice.fe.stiffness).bottomRightCorner(dofs, dofs));
  const Eigen::Index node24 = 3 * 23 - 12;
  const Eigen::VectorXd under_fz = held.solve(Eigen::VectorXd::Unit(dofs, node24 + 2));
  const Eigen::VectorXd under_fx = held.solve(Eigen::VectorXd::Unit(dofs, node24));
  const std::vector<Channel> in{parse_channel(m, "bar@24:fz", true), parse_channel(m, "bar@24:fx", true)};
  const std::vector<Channel> out{parse_channel(m, "bar@24:z", false), parse_channel(m, "bar@24:x", false)};
  const FrequencyResponse r = frequency_response(lm, in, out, {1e-3});
  const Eigen::MatrixXcd& h = r.h.front();
  CHECK(h(0, 0).real() == Approx(under_fz[node24 + 2]).epsilon(3e-5));
  CHECK(h(1, 0).real() == Approx(under_fz[node24]).epsilon(3e-5));
  CHECK(h(0, 1).real() == Approx(under_fx[node24 + 2]).epsilon(3e-5));
  CHECK(h(1, 1).real() == Approx(under_fx[node24]).epsilon(3e-5));
  CHECK(std::abs(h(0, 0).imag()) < 1e-12 * std::abs(h(0, 0)));
  // The state-space model's static gain D - C A^-1 B is the same compliance.
  const StateSpace s = state_space(lm, in, out);
  const Eigen::MatrixXd a = Eigen::MatrixXd(s.A);
  const Eigen::MatrixXd gain = Eigen::MatrixXd(s.D) - Eigen::MatrixXd(s.C) * a.partialPivLu().solve(Eigen::MatrixXd(s.B));
  CHECK(gain(0, 0) == Approx(under_fz[node24 + 2]).epsilon(3e-5));
  CHECK(gain(1, 1) == Approx(under_fx[node24]).epsilon(3e-5));
}

namespace {

// A stiff lattice (2e9 N/m springs: modes in the kHz) on a rigid spherical joint at its
// end node 1, gravity along `down`: the static equilibrium within `most` iterations hangs
// the frame (the part's centre of mass) straight below the pivot, not above it.
void check_hangs_below_pivot(const Eigen::Vector3d& down, int most) {
  Model m = flexible_model(bar_part(6, {1, 2, 3, 24}, 2e9));
  m.gravity = {9.81 * down.x(), 9.81 * down.y(), 9.81 * down.z()};
  hold_nodes(m, 1, 0.0);
  MultibodySystem sys(m);
  const Equilibrium e = find_equilibrium(sys, 0.0, sys.initial_state(), EquilibriumOptions{});
  INFO(e.iterations << " iterations, residual " << e.residual);
  CHECK(e.iterations <= most);
  const StateLayout& l = sys.layout();
  const FlexibleBody& f = sys.model().flexible.front();
  const Eigen::Vector3d pivot = e.state.segment<3>(l.position(f.nodes[0])), frame = e.state.segment<3>(l.position(f.frame));
  CHECK((frame - pivot).normalized().dot(down) > 1.0 - 1e-8);
  CHECK((frame - pivot).norm() > 0.4);
}

}  // namespace

TEST_CASE("flexible body on a rigid pivot, released off its hanging state: the static equilibrium hangs it in a few iterations",
          "[analysis][flexible][joints][modes]") {
  // Gravity 0.3 rad off the level bar's normal. Each step's drift off the joint is taken
  // back with the step's own matrix (equilibrium.cpp: settle_on_joints): a mass-weighted
  // projection moves the stiff modes, and the iteration spent its 500 steps on the forces
  // that made.
  check_hangs_below_pivot({std::sin(0.3), 0.0, -std::cos(0.3)}, 30);
}

TEST_CASE("flexible body on a spherical pivot released exactly level: the static equilibrium hangs it below the pivot",
          "[analysis][flexible][joints][modes]") {
  // Level, the pivot has no stiffness in two directions: K + M / h^2 grows near singular
  // along them as h grows, and its steps, cut to the turn limit, went nowhere (140 N left
  // after 500 iterations) until h stopped growing where the potential fell far less than
  // the step's quadratic model said.
  check_hangs_below_pivot({0.0, 0.0, -1.0}, 40);
}
