#pragma once
// Frequency response of a linearised model: for a harmonic force or torque at some bodies,
// the steady motion of others, H(i omega) from the complex sparse solve of
//   (-omega^2 M + i omega D + K) x = B u,  C x = 0
// (augmented with the rigid joints' rows, KLU), and the linear model as a state-space
// system A, B, C, D for control design.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <complex>
#include <string>
#include <vector>

#include "mbsflow/analysis/linearization.hpp"

namespace mbsflow {

// One coordinate of one body: dof 0..2 translation (force) along x y z, 3..5 rotation
// (torque) about x y z, world frame.
struct Channel {
  int body = 0;  // system body index (a free body, or a flexible body's node)
  int dof = 0;
  enum class Kind { displacement, velocity, acceleration } kind = Kind::displacement;  // outputs only
};

// "BODY:fx" (inputs: fx fy fz tx ty tz) or "BODY:x" (outputs: x y z rx ry rz, v... for
// velocity, a... for acceleration: vx, arx); InputError naming what is wrong.
Channel parse_channel(const Model& model, const std::string& text, bool input);
std::string channel_name(const Model& model, const Channel& c, bool input);

struct FrequencyResponse {
  std::vector<double> frequency;      // Hz
  std::vector<Eigen::MatrixXcd> h;    // per frequency: outputs x inputs, output per unit input
};

// InputError for a channel on a driven body or an empty list.
FrequencyResponse frequency_response(const LinearModel& model, const std::vector<Channel>& inputs,
                                     const std::vector<Channel>& outputs, const std::vector<double>& hz);

// The first-order model z' = A z + B u, y = C z + D u on the motions the joints allow
// (z: their coordinates and rates; without rigid joints the bodies' own).
struct StateSpace {
  Eigen::SparseMatrix<double> A, B, C, D;
};
StateSpace state_space(const LinearModel& model, const std::vector<Channel>& inputs, const std::vector<Channel>& outputs);

// Writes a matrix in Matrix Market coordinate format (real general).
void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& a);

}  // namespace mbsflow
