#pragma once
// The XDMF sidecar of a modes file: each mode animated over one period for ParaView's
// default reader. Time k + f/F is mode k (1-based) at phase 2 pi f/F, so the animation
// plays the modes one after another and time 3.25 is mode 3 a quarter of a period in.
// Each frame is the bodies as points at the equilibrium moved by the scaled shape
// (position, orientation), with the mode's translation shape, the bodies' kinetic share and
// index as point data and the mode number and frequency as field data.
//
// Xdmf3 reads whole datasets only (no hyperslabs, see xdmf_writer.hpp), so the frames are
// datasets of their own under /xdmf/mode<k>/<f>/ in the modes file. They are capped at
// modes_xdmf_frame_limit_bytes: fewer frames per mode, down to 4, and below that one
// still picture per mode (the shape as a vector to warp by).
#include <hdf5.h>

#include <cstddef>
#include <string>
#include <vector>

#include "mbsflow/analysis/modes.hpp"

namespace mbsflow {

inline constexpr int modes_xdmf_frames = 16;  // per period
inline constexpr std::size_t modes_xdmf_frame_limit_bytes = std::size_t{64} << 20;

struct ModesXdmf {
  int frames = 0;        // per mode; 0: still pictures only
  double amplitude = 0;  // the largest body translation drawn, m (a twentieth of the model's size)
  std::string text;      // the sidecar, naming the modes file by h5_name
};

// Writes the frames into `file` (open for writing) and returns the sidecar's text.
// shape_re, shape_im: every body's shape per mode (mode j, body b, coordinate e at
// (j bodies + b) 6 + e), as the modes file holds them.
ModesXdmf write_mode_frames(hid_t file, const LinearModel& lm, const Modes& modes, const std::vector<double>& shape_re,
                            const std::vector<double>& shape_im, const std::string& h5_name);

}  // namespace mbsflow
