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
// written into the sidecar as text; a whole row that lies in one piece in the results file
// (a series of up to 256 bodies or joints: its chunks hold whole rows, unfiltered) is a
// binary DataItem that reads those bytes where they lie (Seek), which costs nothing to make;
// the columns of a series (per-body energies, joint forces) are gathered once into one
// contiguous table per quantity (/xdmf/columns/<name>, a row per snapshot of the sidecar)
// and read in place the same way; the others (rows of a larger model, columns beyond
// xdmf_column_limit_bytes) are datasets of the results file's group /xdmf
// (/xdmf/<row>/<name>), which every HDF5 reader sees as plain N x k arrays. A dataset
// costs about 20 us to make, whatever its kind: 1000 snapshots of seven quantities took
// more than a second's run's 5 %. For a series of at most
// xdmf_copy_limit_bytes those are copies of its rows (compact datasets where they fit); for
// larger ones, HDF5 virtual datasets, which hold no data of their own but cost about five
// times as much to make. A binary item is only as good as the results file stays as it is:
// a tool that rewrites the file (h5repack) moves the rows; `mbsflow run` writes the sidecar
// anew when it resumes.
#include <hdf5.h>

#include <optional>
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

// The size up to which the views of a column of a series (a body's energies, a joint's
// force) are gathered, at the sidecar's rows, into one table the sidecar reads in place
// (xdmf_writer.cpp's ColumnTables); a larger one's views are datasets per snapshot.
inline constexpr std::size_t xdmf_column_limit_bytes = std::size_t{64} << 20;

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
  h5::Handle set, space;
  std::vector<hsize_t> extent;
  std::vector<double> values;  // row-major T x item, when its views are copies or text
  // whole_rows: every view of it is a whole row, so its values are read only where a row
  // is text (inline_view_values) or cannot be read where it lies (row_offset).
  Source(hid_t file, const char* p, bool whole_rows = false);
  // Where row `row` lies in the file as raw little-endian doubles, when its rows are whole
  // in the series' chunks (up to 256 bodies or joints: hdf5_sink.cpp) and those are stored
  // as they are (no filter), which is how the sink writes them; else nothing.
  std::optional<hsize_t> row_offset(hsize_t row) const;

 private:
  hsize_t chunk_rows_ = 0;  // time rows per chunk where rows are whole in chunks, else 0
  hsize_t base_ = 0;        // the file's user block: chunk addresses count from its end
  mutable hsize_t chunk_at_ = 0;  // the last chunk looked up (its first row), and where it lies
  mutable std::optional<haddr_t> chunk_address_;
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
