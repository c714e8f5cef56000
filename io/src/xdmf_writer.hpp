#pragma once
// XDMF sidecar of a results file, so that ParaView opens a run with either of its XDMF
// readers: per snapshot, the bodies as points (velocity, angular velocity, orientation,
// kinetic and gravity energy, body index; the model's energies as values of the grid) and the joints as lines between
// their attachment points (force, torque and joint index per line).
//
// ParaView's default reader (Xdmf3) does not read XDMF hyperslabs (it skips their arrays
// and shows 0 points), so the sidecar does not select rows of the T x N x k series itself:
// the results file gets a group /xdmf of HDF5 virtual datasets, one per snapshot and
// quantity (/xdmf/<row>/<name>), each a view of one row of a series. They hold no data of
// their own, and every HDF5 reader sees them as plain N x k arrays.
#include <hdf5.h>

#include <string>
#include <vector>

#include "mbsflow/io/result_fields.hpp"

namespace mbsflow {

// The sidecar shows at most this many snapshots, evenly spread with the first and last:
// each view costs about 70 us to make (HDF5 1.10), so a run of 12 000 snapshots would
// spend 4 s on them. The results file keeps every snapshot.
inline constexpr std::size_t xdmf_max_steps = 1000;

struct XdmfContent {
  std::size_t bodies = 0, joints = 0;
  std::vector<const BodyField*> body_fields;  // the body fields written (position first)
  bool joint_attachment = false;         // /joints/attachment: the joints as lines
  bool joint_force = false;
  bool energy = false;
  bool body_energy = false;  // /bodies/energy: per body kinetic and gravity energy
};

// Makes the views in `file` (open for writing, its series flushed) and writes the sidecar.
void write_xdmf(hid_t file, const std::string& xdmf_path, const std::string& h5_path, const std::vector<double>& times,
                const XdmfContent& content);

}  // namespace mbsflow
