#pragma once
// Elastic beams as bodies and bushings: a beam of N elements becomes N + 1 node bodies
// (NAME.0 at the first point to NAME.N at the last) and N element bushings (NAME.e0 ..),
// so that everything that works on bodies and bushings (partitions, cuts, implicit
// methods with the analytic Jacobian, modes, checkpoints, results) works on beams.
//
// Each element is two rigid arms of half its length, from its nodes to its midpoint,
// joined there by a bushing in the element's frame (x along it, y the section's y) with
//   axial EA/L, shear 12 E Iz/(L^3 (1 + Phi_y)) along y and 12 E Iy/(L^3 (1 + Phi_z))
//   along z, torsion G J/L, bending E Iy/L about y and E Iz/L about z,
// Phi = 12 E I/(G A_s L^2) with shear deformation (Timoshenko), else 0. For small motions
// this is exactly the two-node Euler-Bernoulli (Timoshenko) element's 12 x 12 stiffness;
// for large ones the bushing measures its deflection in the element's turning frame and its
// rotation as the rotation vector of the two arms' relative orientation (valid up to half
// a turn per element), and its forces are the gradient of its elastic energy, so geometric
// stiffening comes from the formulation itself and an undamped beam conserves energy.
// Mass is lumped at the nodes: each node carries the mass of half of each element beside
// it and the inertia of that piece as a rod of the section.
#include <string>
#include <vector>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

struct BeamSection {
  double area = 0.0;                        // m^2
  double Iy = 0.0, Iz = 0.0;                // integral of z^2 dA and of y^2 dA, m^4
  double J = 0.0;                           // torsion constant, m^4
  double shear_area_y = 0.0, shear_area_z = 0.0;  // Timoshenko only; 0: 5/6 of the area
};

struct BeamSpec {
  std::string name;
  std::vector<Vec3> points;  // the nodes, world frame: at least 2, no two alike in a row
  Vec3 up{0.0, 1.0, 0.0};    // the section's y: made perpendicular to the axis at each node
  double E = 0.0, G = 0.0, density = 0.0;
  BeamSection section;
  bool shear = false;           // Timoshenko (shear deformation), else Euler-Bernoulli
  double stiffness_damping = 0.0;  // beta, s: each element's damping is beta times its stiffness
  // alpha, 1/s: each node damped against its absolute motion by alpha times its mass and
  // inertia (Rayleigh's alpha M; it damps rigid motion too: for structures held still)
  double mass_damping = 0.0;
};

struct BeamParts {
  std::vector<Body> nodes;
  std::vector<Joint> elements;  // between nodes first_body + i and first_body + i + 1
  std::vector<Load> loads;      // the nodes' mass-proportional damping, with mass_damping
};

// The nodes of a straight beam from `from` to `to` in `elements` equal elements.
std::vector<Vec3> straight_beam_points(const Vec3& from, const Vec3& to, int elements);

// The beam's nodes and elements, its first node to be body `first_body` of the model.
// InputError (naming the field) for bad numbers, fewer than 2 points, two points alike in
// a row, or `up` along the axis at a node.
BeamParts make_beam(const BeamSpec& spec, int first_body);

// Appends the beam to the model (its bodies' and joints' names must be new there) and
// records it in model.beams.
void add_beam(Model& model, const BeamSpec& spec);

}  // namespace mbsflow
