#pragma once
// Natural modes of a linearised model: the eigenvalues lambda of
//   (lambda^2 M + lambda D + K) x = 0,  C x = 0
// (damped, complex: frequency |lambda| / 2 pi, damping ratio -Re lambda / |lambda|), or of
// K x = omega^2 M x without damping. Rigid joints are held exactly: a null-space basis of
// C for models solved dense, the augmented pencil [K C^T; C 0] for the sparse
// shift-invert solver (Spectra, on a KLU factorisation), so that no constraint direction
// shows up as a mode.
#include <Eigen/Dense>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "mbsflow/analysis/linearization.hpp"

namespace mbsflow {

enum class ModeSolver { automatic, dense, sparse };

struct ModeOptions {
  int count = 10;          // the lowest modes wanted (all there are where fewer)
  bool damped = true;      // complex modes of M, D, K; else K x = omega^2 M x (D left out)
  // Dense up to dense_limit coordinates left free, or where a quarter of them are asked for.
  // The dense first-order eigensolver (all 2n values and vectors) grows as n^3 from 1.2 s
  // at 300 free coordinates (11.7 s at 600, 194 s at 1200); the sparse one takes 0.1 s there.
  ModeSolver solver = ModeSolver::automatic;
  static constexpr Eigen::Index dense_limit = 200;
  // Told where the sparse solver turns to a slower path (Spectra's restarts, minutes on a
  // large model): a command line says so before the wait.
  using Notice = std::function<void(const std::string&)>;
  Notice notice;
};

struct Modes {
  std::vector<std::complex<double>> eigenvalue;  // lambda (1/s), ascending |lambda|; Im >= 0
  std::vector<double> frequency;                 // Hz: |lambda| / 2 pi (undamped natural frequency)
  std::vector<double> damping_ratio;             // -Re lambda / |lambda|; 0 for a rigid-body mode
  std::vector<bool> rigid_body;                  // lambda zero to rounding: a motion without stiffness
  Eigen::MatrixXcd shape;                        // n x modes: the coordinates x (LinearModel), x^H M x = 1
  Eigen::MatrixXd kinetic_share, strain_share;   // free bodies x modes: each body's share of the mode's energies
  std::vector<double> residual;                  // |(lambda^2 M + lambda D + K) x| / scale, on the allowed motions
  Eigen::Index free_coordinates = 0;             // coordinates less independent constraints
  std::string solver;                            // which solver found them
};

// InputError for a count < 1; RunError when the sparse solver does not converge.
Modes compute_modes(const LinearModel& model, const ModeOptions& options);

}  // namespace mbsflow
