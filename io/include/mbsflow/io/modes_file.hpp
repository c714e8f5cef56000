#pragma once
// The results of mbsflow modes as one HDF5 file:
//   /modes/frequency (K, Hz, ascending), /modes/damping_ratio (K), /modes/eigenvalue (K x 2:
//   real and imaginary part, 1/s), /modes/rigid_body (K, 1 for a motion without stiffness),
//   /modes/residual (K), /modes/shape (K x N x 6: translation m and rotation rad per body,
//   world frame, mass-normalised; the real part), /modes/shape_imag (its imaginary part),
//   /modes/energy_share (K x N x 2: each body's share of the kinetic and strain energy),
//   /bodies/names (N), /equilibrium/position (N x 3), /equilibrium/orientation (N x 4),
// the model and the command as attributes, units on each dataset. Driven bodies have
// zero shapes. Written under FILE.part and renamed when complete. /xdmf holds the frames
// of the XDMF sidecar FILE.xdmf (each mode animated over a period for ParaView; time k + f
// is mode k at the fraction f of its period), written beside it.
#include <string>

#include "mbsflow/analysis/modes.hpp"

namespace mbsflow {

struct ModesFileInfo {
  std::string model_json;
  std::string command_line;
  std::string linearised_at;  // "static equilibrium", "initial state", "t = 1.5 s of r.h5"
};

struct ModesFileWritten {
  std::string xdmf;  // the sidecar's path
  int frames = 0;    // per mode (0: one still picture per mode, the model being too large)
};

ModesFileWritten write_modes_file(const std::string& path, const LinearModel& model, const Modes& modes,
                                  const ModesFileInfo& info);

}  // namespace mbsflow
