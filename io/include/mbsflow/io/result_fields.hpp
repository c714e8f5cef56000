#pragma once
// The fields a results file can hold, shared by the HDF5 writer and reader, the XDMF
// sidecar and the CSV export.
#include <array>
#include <string>
#include <vector>

#include "mbsflow/graph/state_layout.hpp"

namespace mbsflow {

struct BodyField {
  const char* name;     // as in --fields
  const char* dataset;  // HDF5 path, T x N x components
  int components;
  std::array<const char*, 4> columns;  // CSV column names
  const char* unit;                     // SI, stored as the dataset's "units" attribute
  Eigen::Index (StateLayout::*offset)(Eigen::Index) const;  // where body i's values start in the state
};

// In the state's order (state_fields), whose offsets and widths they take.
inline constexpr std::array<BodyField, 4> body_fields{{
    {"position", "/bodies/position", state_fields[0].width, {"x", "y", "z", ""}, "m", state_fields[0].offset},
    {"orientation", "/bodies/orientation", state_fields[1].width, {"qw", "qx", "qy", "qz"}, "1", state_fields[1].offset},
    {"velocity", "/bodies/velocity", state_fields[2].width, {"vx", "vy", "vz", ""}, "m/s", state_fields[2].offset},
    {"angular_velocity", "/bodies/angular_velocity", state_fields[3].width, {"wx", "wy", "wz", ""}, "rad/s",
     state_fields[3].offset},
}};

inline constexpr const char* energy_dataset = "/energy";        // T x 3: kinetic, gravity, elastic
// T x N x 2: each body's kinetic energy and potential of gravity (their sums are the first
// two columns of /energy), written with the energies.
inline constexpr const char* body_energy_dataset = "/bodies/energy";
inline constexpr const char* joint_force_dataset = "/joints/force";  // T x J x 6
// T x J x 1: torque or force of each joint's motor along its axis (0 without a motor);
// written with joint_force when the model has a motor.
inline constexpr const char* motor_effort_dataset = "/joints/motor_effort";
// T x J x 6: each joint's two attachment points in the world (x1 y1 z1 x2 y2 z2), written
// with the positions when the model has joints: the joints as lines in ParaView and the viewer.
inline constexpr const char* joint_attachment_dataset = "/joints/attachment";
// T x E: the flexible bodies' modal coordinates (docs/flexible.md), body after body in the
// model's order; /flexible/names and /flexible/modes say whose and how many. Written with
// the positions when the model has flexible bodies.
inline constexpr const char* modal_coordinates_dataset = "/flexible/modal_coordinates";
inline constexpr const char* modal_coordinates_unit = "m kg^0.5 (mass-normalised modes)";
// T x E x 6: each beam element's section forces at its midpoint in the element's frame
// (axial, shear y, shear z, torsion, bending y, bending z), beams in the model's order;
// written with joint_force when the model has beams.
inline constexpr const char* beam_section_force_dataset = "/beams/section_force";

// Units of the other series ("units" attribute of each dataset; body fields carry theirs).
inline constexpr const char* time_unit = "s";
inline constexpr const char* energy_unit = "J";                 // kinetic, gravity, elastic
inline constexpr const char* joint_force_unit = "N, N m";       // force xyz, torque xyz on body2, world
inline constexpr const char* motor_effort_unit = "N m or N";    // revolute: torque; prismatic: force
inline constexpr const char* joint_attachment_unit = "m";
inline constexpr const char* beam_section_force_unit = "N, N m";  // N Vy Vz, T My Mz

struct FieldSet {
  std::array<bool, 4> body{true, true, true, true};  // in the order of body_fields
  bool energy = true;
  bool joint_force = false;
};

// At most `most` of `rows` snapshots (indices), evenly spread, the first and the last
// among them: what the XDMF sidecar and the viewer show of a long run.
std::vector<std::size_t> evenly_spread_rows(std::size_t rows, std::size_t most);

// "position,velocity,energy" -> FieldSet; "all" selects everything. Throws InputError.
FieldSet parse_fields(const std::string& list);
std::string fields_text(const FieldSet& f);

}  // namespace mbsflow
