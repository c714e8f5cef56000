#pragma once
// The model as plain data: bodies, joints, loads, drivers and run settings.
// Readers (io/), generators and embedding programs fill it; MultibodySystem compiles it.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mbsflow/graph/flexible_body.hpp"
#include "mbsflow/graph/force_table.hpp"
#include "mbsflow/graph/rare_value.hpp"
#include "mbsflow/method.hpp"
#include "mbsflow/graph/time_function.hpp"

namespace mbsflow {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // w, x, y, z
using Vec6 = std::array<double, 6>;  // x, y, z, rx, ry, rz
inline constexpr Quat identity_frame{1.0, 0.0, 0.0, 0.0};
inline constexpr Vec3 zeros3{};
inline constexpr Vec6 zeros6{};
inline constexpr Vec6 unit_inertia{1.0, 1.0, 1.0, 0.0, 0.0, 0.0};

inline constexpr int ground = -1;  // body index of the fixed world frame

struct Body {
  std::string name;
  double mass = 1.0;
  // Inertia tensor about the centre of mass in the body frame:
  // Ixx, Iyy, Izz, Ixy, Ixz, Iyz (tensor entries, i.e. Ixy = -integral of x*y dm).
  // One pointer, shared by bodies with the same (Defaulted, ValueSharing).
  Defaulted<Vec6, unit_inertia> inertia;
  Vec3 position{};                     // world, centre of mass
  Quat orientation{1.0, 0.0, 0.0, 0.0};  // body to world
  Vec3 velocity{};                     // world
  Vec3 angular_velocity{};             // body frame
};

enum class JointType { bushing, spring, revolute, spherical, prismatic, cylindrical, universal, planar, fixed, distance, screw };

// The kinematic joints (revolute ... distance) constrain the relative motion of their
// two frames; the others are force elements.
inline bool is_kinematic(JointType t) { return t != JointType::bushing && t != JointType::spring; }
const char* joint_type_name(JointType t);

// A motor on a revolute (angle, torque) or prismatic (displacement, force) joint, along
// the joint axis (z of the joint frames): a time function prescribes the position, the
// velocity, or the effort.
struct JointMotor {
  enum class Kind { none, position, velocity, effort };
  Kind kind = Kind::none;
  TimeFunction function = TimeFunction::constant(0.0);
};

// Joint limits on a revolute (angle, rad) or prismatic (displacement, m) joint: beyond
// them a one-sided spring-damper stop pushes back.
struct JointLimits {
  bool active = false;
  double lower = 0.0, upper = 0.0;
  double stiffness = 0.0, damping = 0.0;
};

// A joint between body1 (or ground) and body2.
// bushing: 6-axis spring-damper in the joint frame (frame1 on body1 at point1),
//          force on body2 = -(K d + C d' - preload), rotations by the rotation vector
//          of the relative orientation (valid for large rotations up to pi).
// spring:  point-to-point spring-damper along the line between the two points.
// kinematic joints: constraints between the joint frame on body1 (frame1 at point1) and
//          the one on body2 (frame2 at point2); the joint axis is z of the frames. Rigid:
//          exact constraints; compliant (rigid = false): on each constrained direction the
//          seed's reaction -(k phi + c phi'), k and c from frequency and damping ratio like
//          a bushing's (stored in stiffness/damping per axis).
struct Joint {
  std::string name;
  JointType type = JointType::bushing;
  int body1 = ground;
  int body2 = 0;
  bool rigid = true;  // kinematic joints: exact constraint, or compliant
  // Each of the values below is one pointer (Defaulted): null at its default, else a value
  // that joints with the same one may share (RecentValues), so that a million joints stay
  // small (136 bytes; 256 as values).
  Defaulted<Vec3, zeros3> point1;  // in body1's frame (world frame for ground)
  Defaulted<Vec3, zeros3> point2;  // in body2's frame
  Defaulted<Quat, identity_frame> frame1;  // joint frame relative to body1
  Defaulted<Quat, identity_frame> frame2;  // joint frame relative to body2 (at rest)
  Defaulted<Vec6, zeros6> stiffness;  // bushing: per axis; spring: stiffness[0]
  Defaulted<Vec6, zeros6> damping;    // bushing: per axis; spring: damping[0]
  AxisTables tables;                  // nonlinear force(deflection) per axis; empty = linear
  Defaulted<Vec6, zeros6> preload;    // force/torque on body2 at zero deflection, joint frame
  double rest_length = 0.0;           // spring: rest length; distance: the rod's length; screw: the lead (m per turn)
  // Revolute and prismatic only; few joints have them, so each is behind a pointer.
  RareValue<JointMotor> motor;
  RareValue<JointLimits> limits;
};

// Offers each joint's and body's values to the next ones' (RecentValues): a reader or
// generator passes its joints and bodies through one of these in order.
struct ValueSharing {
  RecentValues<Defaulted<Vec3, zeros3>> points;
  RecentValues<Defaulted<Quat, identity_frame>> frames;
  RecentValues<Defaulted<Vec6, zeros6>> laws;  // stiffness, damping and preload
  RecentValues<Defaulted<Vec6, unit_inertia>> inertias;
  void operator()(Joint& j) {
    points.share(j.point1);
    points.share(j.point2);
    frames.share(j.frame1);
    frames.share(j.frame2);
    laws.share(j.stiffness);
    laws.share(j.damping);
    laws.share(j.preload);
  }
  void operator()(Body& b) { inertias.share(b.inertia); }
};

struct Load {
  int body = 0;
  Vec3 force{};     // scaled by function(t)
  Vec3 torque{};    // scaled by function(t)
  Vec3 point{};     // application point of the force, body frame
  bool body_frame = false;  // force and torque given in the body frame
  TimeFunction function{};  // constant 1 by default
  // Damping against the body's absolute motion, not scaled by the function: a force
  // -damping .* v (per world axis, N s/m) and a torque -R C w (C the body-frame matrix of
  // angular_damping, N m s, laid out as an inertia). The mass-proportional (Rayleigh alpha)
  // damping of a beam's nodes (docs/beams.md).
  Vec3 damping{};
  Vec6 angular_damping{};
  bool damped() const { return damping != Vec3{} || angular_damping != Vec6{}; }
};

// Kinematic excitation: the body's position follows
// initial position + velocity * t + (x(t), y(t), z(t)); its orientation stays fixed.
struct Driver {
  int body = 0;
  Vec3 velocity{};
  std::array<TimeFunction, 3> displacement{TimeFunction::constant(0.0), TimeFunction::constant(0.0),
                                           TimeFunction::constant(0.0)};
};

struct SimulationSettings {
  double t_start = 0.0;
  double t_end = 1.0;
  std::optional<double> step;  // none: RK4 picks a stable step
  // None: chosen for the model (options_from_model): RK4 with the stable step of its
  // stiffest joint, or DOPRI5 where no joint gives one (rigid joints only, say).
  std::optional<Method> method;
  // Method-specific: tirk's tableau and/or iteration ("radau3", "newton", "radau5,newton-triangular"),
  // colloc's "m,s[,order]"; empty: the method's default.
  std::string variant;
  // Write every k-th step (RK4) or every k*step (DOPRI5); none: about a thousand
  // snapshots over the run (options_from_model).
  std::optional<int> output_every;
  // The output grid in s of model time, whatever the method's steps; overrides output_every.
  std::optional<double> output_interval;
  double rtol = 1e-6;
  double atol = 1e-8;
  // Rigid joints violated at the start by more than assembly_tolerance (m, rad) are an
  // error unless assemble is set: then the bodies are moved onto the joints.
  bool assemble = false;
  static constexpr double assembly_tolerance = 1e-5;
};

class ForceElement;  // force_element.hpp

// Where an elastic beam's parts lie in its model (beams.hpp): the beam is its node bodies
// and element bushings; this names them together, for the results' centrelines.
struct BeamRecord {
  std::string name;
  int first_body = 0, nodes = 0;      // bodies first_body .. first_body + nodes - 1, in order
  int first_joint = 0, elements = 0;  // element bushings, first_joint + i between nodes i and i + 1
};

struct Model {
  std::string name = "model";
  Vec3 gravity{};
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Load> loads;
  std::vector<Driver> drivers;
  SimulationSettings simulation;
  // User force elements (code of this program, not part of a model file): every run in
  // this process applies them, partitioned and loosely coupled ones included; a run
  // across worker processes refuses them.
  std::vector<std::shared_ptr<const ForceElement>> force_elements;
  std::vector<BeamRecord> beams;
  // Reduced finite-element bodies on floating frames: each one's frame and interface
  // nodes are bodies of the list above, its modal coordinates the state's tail.
  std::vector<FlexibleBody> flexible;
};

// Checks every field of the model (finite numbers, positive masses and inertias, body
// indices in range, unit-able quaternions, time functions, run settings); InputError
// naming the first bad field. MultibodySystem calls it, so every run does.
void check_model(const Model& model);

// Index of the body called name, ground for "ground", nullopt if unknown.
std::optional<int> find_body(const Model& model, const std::string& name);

// The seed's natural-frequency form of a bushing: stiffness m*Omega^2 and damping
// 2*mu*Omega*m per axis, with m the reduced mass (translations) or the reduced
// moment of inertia about that axis (rotations) of the two bodies it joins.
void set_bushing_from_frequency(const Model& model, Joint& joint, double omega, double mu);

}  // namespace mbsflow

namespace mbsflow {
// The joint frame on body2 that makes the joint's initial rotational deflection zero:
// q1 (x) frame1 = q2 (x) frame2 in the initial configuration.
Quat rest_frame2(const Model& model, const Joint& joint);
}  // namespace mbsflow
