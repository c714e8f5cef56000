#pragma once
// The IFToMM multibody benchmark problems shipped in examples/models, and their reference:
// each mechanism's reduced equations in generalised coordinates, integrated independently
// of the multibody code (RK4 with a small fixed step), compared with a run's snapshots.
// `mbsflow bench iftomm` and the tests share this, so both measure the same thing.
#include <Eigen/Core>
#include <span>
#include <vector>

#include "mbsflow/graph/multibody_system.hpp"

namespace mbsflow {

enum class IftommProblem { a01_pendulum, a02_n_four_bar, a05_flyball_governor };

struct IftommInfo {
  IftommProblem id;
  const char* title;      // with the span
  const char* file;       // in examples/models
  const char* error_of;   // the benchmark's named coordinate
  const char* drift_of;   // the conserved quantity whose drift is reported
  const char* published;  // what other codes report (docs/joints.md gives the sources)
};

std::span<const IftommInfo> iftomm_problems();

struct IftommCheck {
  double error = 0.0;  // largest distance (m) of the named coordinate from the reference
  double drift = 0.0;  // largest |Q(t) - Q(0)| of the conserved quantity
};

// times[k], states[k]: a run's snapshots from t = 0, of the example model `sys` was built from.
IftommCheck check_iftomm(IftommProblem p, MultibodySystem& sys, const std::vector<double>& times,
                         const std::vector<Eigen::VectorXd>& states);

}  // namespace mbsflow
