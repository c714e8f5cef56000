#pragma once
// What modes.cpp and its sparse eigensolvers share: a mode as found, the scale against
// which an eigenvalue counts as zero, and the two solvers (Lanczos for the undamped
// modes, the Arnoldi on the first-order pencil for the damped ones and where the Lanczos
// does not serve).
#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <vector>

#include "mbsflow/analysis/linearization.hpp"
#include "mbsflow/analysis/modes.hpp"

namespace mbsflow {

// A mode found by a solver: its eigenvalue and its coordinates x.
struct FoundMode {
  std::complex<double> lambda;
  Eigen::VectorXcd x;
  bool rigid = false;
};

// An eigenvalue below this fraction of modal_rate_scale counts as zero (a rigid-body
// motion): a zero eigenvalue is a Jordan pair of the first-order pencil, which rounding
// splits by about sqrt(machine epsilon) of the scale, and a 100 000-link chain's lowest
// vibration lies at 2e-6 of it.
constexpr double zero_rate = 1e-7;

// The speed of the model's fastest motions (rad/s): the scale against which an
// eigenvalue counts as zero.
double modal_rate_scale(const LinearModel& m);

// The lowest undamped modes (K's symmetric part against M) by symmetric shift-invert
// Lanczos on n numbers per vector; nothing where it does not converge or finds a
// rigid-body motion (the Arnoldi then serves).
std::optional<std::vector<FoundMode>> undamped_modes(const LinearModel& m, int count);

// The lowest modes by shift-invert Arnoldi on the first-order pencil (2n numbers per
// vector): ours without restarts, or Spectra's restarted one where that does not converge
// (*restarted then true, and notice, where set, told before it starts). RunError where
// neither converges.
std::vector<FoundMode> first_order_modes(const LinearModel& m, int count, bool damped, bool* restarted,
                                         const ModeOptions::Notice& notice = nullptr);

}  // namespace mbsflow
