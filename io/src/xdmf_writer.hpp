#pragma once
// XDMF sidecar of a results file, so that ParaView opens a run with either of its XDMF
// readers: per snapshot, the bodies as points (velocity, angular velocity, orientation,
// kinetic and gravity energy, body index; the model's energies as values of the grid), the joints as lines between
// their attachment points (force, torque and joint index per line), elastic beams as
// polylines through their nodes (beam and element joint index per segment), and flexible
// bodies' surfaces deformed (flexible_surface.hpp).
//
// ParaView's default reader (Xdmf3) does not read XDMF hyperslabs (it skips their arrays
// and shows 0 points), so the sidecar does not select rows of the T x N x k series itself:
// each snapshot and quantity gets a view of one row of a series: a view of a few values is
// written into the sidecar as text; the others are datasets of the results file's group
// /xdmf (/xdmf/<row>/<name>), which every HDF5 reader sees as plain N x k arrays. For a
// series of at most xdmf_copy_limit_bytes those are copies of its rows (compact datasets
// where they fit); for larger ones, HDF5 virtual datasets, which hold no data of their own
// but cost about five times as much to make.
#include <hdf5.h>

#include <ostream>
#include <string>
#include <vector>

#include "flexible_surface.hpp"
#include "hdf5_handle.hpp"
#include "mbsflow/io/result_fields.hpp"

namespace mbsflow {

// The sidecar shows at most this many snapshots, evenly spread with the first and last:
// each virtual view costs about 70 us to make (HDF5 1.10), so a run of 12 000 snapshots would
// spend 4 s on them. The results file keeps every snapshot.
inline constexpr std::size_t xdmf_max_steps = 1000;

// The size of a series up to which its views are copies of its rows: a copy takes about a
// fifth of the time a virtual dataset takes to make and a quarter to close (8000 views of 4
// x 3 values: 0.30-0.47 s and 0.06 s against 1.46-1.57 s and 0.22-0.35 s, HDF5 1.10), and
// the file grows by at most the series' own size.
inline constexpr std::size_t xdmf_copy_limit_bytes = std::size_t{1} << 20;

struct XdmfContent {
  std::size_t bodies = 0, joints = 0;
  std::vector<const BodyField*> body_fields;  // the body fields written (position first)
  bool joint_attachment = false;         // /joints/attachment: the joints as lines
  bool joint_force = false;
  bool energy = false;
  bool body_energy = false;  // /bodies/energy: per body kinetic and gravity energy
  // Elastic beams' elements as lines between their nodes' centres (a beam's centreline):
  // per element its two node bodies, its beam and its bushing (joint index).
  std::vector<int> beam_lines, beam_index, beam_joint;
  bool beam_section_force = false;  // /beams/section_force: cell data of the centrelines
  // Flexible bodies with a drawn surface (flexible_surface.hpp), with the orientations and
  // modal coordinates written.
  std::vector<FlexibleSurface> surfaces;
};

// A series that views show rows of: its name and space, read once; and, where the whole
// series is at most xdmf_copy_limit_bytes, its values (its views are then copies).
struct Source {
  const char* path;
  h5::Handle space;
  std::vector<hsize_t> extent;
  std::vector<double> values;  // row-major T x item, when its views are copies
  Source(hid_t file, const char* p) : path(p) {
    const h5::Handle set(H5Dopen2(file, p, H5P_DEFAULT), H5Dclose, std::string("open ") + p);
    space = h5::Handle(H5Dget_space(set.get()), H5Sclose, std::string("get the space of ") + p);
    extent.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
    H5Sget_simple_extent_dims(space.get(), extent.data(), nullptr);
    hsize_t count = 1;
    for (hsize_t e : extent) count *= e;
    if (count == 0 || count * sizeof(double) > xdmf_copy_limit_bytes) return;
    values.resize(count);
    h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), std::string("read ") + p);
  }
};

// A view `name` in `group`, of shape `dims`, of row `row` of `source` (T x item), columns
// [column, column + columns) of its last dimension: a copy where the source was read, else
// a virtual dataset.
void make_view(hid_t group, const char* name, const std::vector<hsize_t>& dims, const Source& source, hsize_t row,
               hsize_t column, hsize_t columns);

// One DataItem reading the dataset `path` of the HDF5 file `file` (named as the sidecar
// names it), and an Attribute holding one.
void xdmf_item(std::ostream& o, const std::string& file, const std::string& path, const std::string& dims, bool integer,
               const char* indent);
void xdmf_attribute(std::ostream& o, const std::string& file, const char* name, const char* type, const char* center,
                    const std::string& path, const std::string& dims, bool integer = false);

// Makes the views in `file` (open for writing, its series flushed) and writes the sidecar.
void write_xdmf(hid_t file, const std::string& xdmf_path, const std::string& h5_path, const std::vector<double>& times,
                const XdmfContent& content);

}  // namespace mbsflow
