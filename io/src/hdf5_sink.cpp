#include "mbsflow/io/hdf5_sink.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <chrono>
#include <optional>
#include <type_traits>
#include <array>
#include <vector>
#include <filesystem>

#include <Eigen/Geometry>

#include "hdf5_handle.hpp"
#include "killed_writer.hpp"
#include "random_id.hpp"
#include "writer_lock.hpp"
#include "mbsflow/version.hpp"
#include "xdmf_writer.hpp"

namespace mbsflow {
namespace {

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr std::size_t buffer_bytes = std::size_t{32} << 20;  // bounds the chunk row kept in memory
constexpr hsize_t chunk_samples = 4096;                       // time rows x bodies per chunk

// An extendible float64 dataset of shape (0, dims...) chunked as (rows, chunk dims...).
struct Series {
  std::string path;
  std::vector<hsize_t> item;   // shape of one time row
  h5::Handle set;
  std::vector<double> buffer;  // rows of this chunk row, row-major
  std::size_t row_size() const {
    std::size_t s = 1;
    for (hsize_t d : item) s *= d;
    return s;
  }
};

Series make_series(hid_t file, const std::string& path, std::vector<hsize_t> item, hsize_t rows, const char* unit) {
  Series s{path, std::move(item), {}, {}};
  std::vector<hsize_t> dims{0}, max{H5S_UNLIMITED}, chunk{rows};
  for (std::size_t i = 0; i < s.item.size(); ++i) {
    dims.push_back(s.item[i]);
    max.push_back(s.item[i]);
    // Along bodies (or joints), as many as fit the chunk's sample budget with these rows.
    chunk.push_back(i == 0 ? std::clamp<hsize_t>(chunk_samples / rows, 1, std::max<hsize_t>(1, s.item[i])) : s.item[i]);
  }
  const h5::Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max.data()), H5Sclose,
                         "create the space of " + path);
  const h5::Handle plist(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create a dataset property list");
  h5::check(H5Pset_chunk(plist.get(), static_cast<int>(chunk.size()), chunk.data()), "chunk " + path);
  const h5::Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose, "create a link property list");
  h5::check(H5Pset_create_intermediate_group(lcpl.get(), 1), "allow intermediate groups");
  s.set = h5::Handle(H5Dcreate2(file, path.c_str(), H5T_IEEE_F64LE, space.get(), lcpl.get(), plist.get(), H5P_DEFAULT),
                     H5Dclose, "create " + path);
  h5::write_string_attribute(s.set.get(), "units", unit);
  return s;
}

// An existing series of a file being resumed, checked against the shape it must have.
Series open_series(hid_t file, const std::string& path, std::vector<hsize_t> item) {
  Series s{path, std::move(item), {}, {}};
  s.set = h5::Handle(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
  const h5::Handle space(H5Dget_space(s.set.get()), H5Sclose, "get the space of " + path);
  std::vector<hsize_t> dims(s.item.size() + 1);
  if (H5Sget_simple_extent_ndims(space.get()) != static_cast<int>(dims.size()) ||
      H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0 ||
      !std::equal(s.item.begin(), s.item.end(), dims.begin() + 1))
    throw InputError(path + " in the results file has another shape than this model's");
  return s;
}

hsize_t rows_of(const Series& s) {
  const h5::Handle space(H5Dget_space(s.set.get()), H5Sclose, "get the space of " + s.path);
  std::vector<hsize_t> dims(s.item.size() + 1);
  h5::check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr), "read the shape of " + s.path);
  return dims[0];
}

void truncate(Series& s, hsize_t rows) {
  std::vector<hsize_t> dims{rows};
  dims.insert(dims.end(), s.item.begin(), s.item.end());
  h5::check(H5Dset_extent(s.set.get(), dims.data()), "shorten " + s.path);
}

// The first `rows` values of a series of one value per row (the times).
std::vector<double> read_rows(const Series& s, hsize_t rows) {
  std::vector<double> v(rows);
  if (rows == 0) return v;
  const h5::Handle file_space(H5Dget_space(s.set.get()), H5Sclose, "get the space of " + s.path);
  const hsize_t start = 0;
  h5::check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &start, nullptr, &rows, nullptr), "select " + s.path);
  const h5::Handle mem(H5Screate_simple(1, &rows, nullptr), H5Sclose, "create a memory space");
  h5::check(H5Dread(s.set.get(), H5T_NATIVE_DOUBLE, mem.get(), file_space.get(), H5P_DEFAULT, v.data()), "read " + s.path);
  return v;
}

// Rows [first_row, first_row + rows) of s, whole, as the dataset's extent once they are
// written, the start and the count of their block.
struct RowBlock {
  std::vector<hsize_t> dims, start, count;
};
RowBlock row_block(const Series& s, hsize_t first_row, hsize_t rows) {
  RowBlock b{{first_row + rows}, {first_row}, {rows}};
  for (hsize_t d : s.item) {
    b.dims.push_back(d);
    b.start.push_back(0);
    b.count.push_back(d);
  }
  return b;
}

// Extends s to b.dims; its file space then, for write_block.
h5::Handle extend(Series& s, const RowBlock& b) {
  h5::check(H5Dset_extent(s.set.get(), b.dims.data()), "extend " + s.path);
  return h5::Handle(H5Dget_space(s.set.get()), H5Sclose, "get the space of " + s.path);
}

// Writes data (row-major, b.count's shape) at b.start of s, already extended.
void write_block(Series& s, const h5::Handle& file_space, const RowBlock& b, const double* data) {
  h5::check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, b.start.data(), nullptr, b.count.data(), nullptr),
            "select rows of " + s.path);
  const h5::Handle mem(H5Screate_simple(static_cast<int>(b.count.size()), b.count.data(), nullptr), H5Sclose,
                       "create a memory space");
  h5::check(H5Dwrite(s.set.get(), H5T_NATIVE_DOUBLE, mem.get(), file_space.get(), H5P_DEFAULT, data), "write " + s.path);
}

// Appends the buffered rows to the dataset.
void append(Series& s, hsize_t first_row) {
  const std::size_t row = s.row_size();
  if (row == 0 || s.buffer.empty()) return;
  const RowBlock b = row_block(s, first_row, s.buffer.size() / row);
  write_block(s, extend(s, b), b, s.buffer.data());
  s.buffer.clear();
}

// Joints [first, last)'s attachment points in the world at state y: body position + R(q)
// point, or the point itself on the ground.
void append_attachment_points(const Model& m, const StateLayout& l, const Eigen::VectorXd& y, std::size_t first,
                              std::size_t last, std::vector<double>& out) {
  auto world = [&](int body, const Vec3& p) {
    const Eigen::Vector3d local(p[0], p[1], p[2]);
    if (body == ground) return local;
    const double* q = y.data() + l.orientation(body);
    const Eigen::Quaterniond r(q[0], q[1], q[2], q[3]);
    return Eigen::Vector3d(y.segment<3>(l.position(body)) + r.normalized() * local);
  };
  for (std::size_t k = first; k < last; ++k) {
    const Joint& j = m.joints[k];
    const Eigen::Vector3d a = world(j.body1, j.point1), b = world(j.body2, j.point2);
    out.insert(out.end(), {a.x(), a.y(), a.z(), b.x(), b.y(), b.z()});
  }
}

// Beam elements [first, last)'s section forces in the element's frame (x along it, y the
// section's y): axial force, shear y, z, torsion, bending about y, z, the resultants on
// the cut face whose outward normal is +x (tension and the moment that the part beyond
// the midpoint exerts positive). The bushing's wrench on its second node is the force
// that the first half exerts on the second: the face's resultant is its opposite.
void append_section_forces(const Model& m, const StateLayout& l, const Eigen::VectorXd& y, const Eigen::VectorXd& wrench,
                           const std::vector<int>& element_joints, std::size_t first, std::size_t last,
                           std::vector<double>& out) {
  for (std::size_t e = first; e < last; ++e) {
    const int j = element_joints[e];
    const Joint& joint = m.joints[static_cast<std::size_t>(j)];
    const double* q = y.data() + l.orientation(joint.body1);
    const Quat& f = joint.frame1;
    const Eigen::Quaterniond frame = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized() * Eigen::Quaterniond(f[0], f[1], f[2], f[3]);
    const Eigen::Matrix3d to_element = frame.toRotationMatrix().transpose();
    const Eigen::Vector3d force = -(to_element * wrench.segment<3>(6 * j)), moment = -(to_element * wrench.segment<3>(6 * j + 3));
    out.insert(out.end(), {force.x(), force.y(), force.z(), moment.x(), moment.y(), moment.z()});
  }
}

// The coupling records as columns of /coupling (in a file not in SWMR mode), in place of
// any there: a resumed run's file holds its predecessor's if that was killed after it
// wrote them, while it closed the file.
void write_coupling_records(hid_t file, const std::vector<CouplingRecord>& records) {
  if (H5Lexists(file, "/coupling", H5P_DEFAULT) > 0)
    h5::check(H5Ldelete(file, "/coupling", H5P_DEFAULT), "remove the coupling records of the run resumed");
  if (records.empty()) return;
  const hsize_t n = records.size();
  const h5::Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose, "create a link property list");
  h5::check(H5Pset_create_intermediate_group(lcpl.get(), 1), "allow intermediate groups");
  auto column = [&](const char* name, hid_t file_type, auto value) {
    using T = decltype(value(records[0]));
    std::vector<T> v;
    for (const CouplingRecord& r : records) v.push_back(value(r));
    const h5::Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose, "create a coupling space");
    const std::string path = std::string("/coupling/") + name;
    const h5::Handle set(H5Dcreate2(file, path.c_str(), file_type, space.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
                         H5Dclose, "create " + path);
    const hid_t memory = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    h5::check(H5Dwrite(set.get(), memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "write " + path);
  };
  column("index", H5T_STD_I64LE, [](const CouplingRecord& r) { return static_cast<std::int64_t>(r.index); });
  column("t_start", H5T_IEEE_F64LE, [](const CouplingRecord& r) { return r.t_start; });
  column("t_end", H5T_IEEE_F64LE, [](const CouplingRecord& r) { return r.t_end; });
  column("position_error", H5T_IEEE_F64LE, [](const CouplingRecord& r) { return r.position_error; });
  column("velocity_error", H5T_IEEE_F64LE, [](const CouplingRecord& r) { return r.velocity_error; });
  column("lag", H5T_STD_I64LE, [](const CouplingRecord& r) { return static_cast<std::int64_t>(r.lag); });
}

h5::Handle file_access() {
  h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "create a file access list");
  h5::check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V110, H5F_LIBVER_LATEST), "set the file format");
  return fapl;
}

// Bodies [first, last)'s kinetic energy (translation and rotation, the angular velocity and
// inertia in the body frame) and potential of gravity, -m g . r, as MultibodySystem::energy
// sums them.
void append_body_energies(const Model& m, const StateLayout& l, const Eigen::VectorXd& y, Eigen::Index first,
                          Eigen::Index last, std::vector<double>& out) {
  const Eigen::Vector3d g(m.gravity[0], m.gravity[1], m.gravity[2]);
  for (Eigen::Index i = first; i < last; ++i) {
    const Body& b = m.bodies[static_cast<std::size_t>(i)];
    const Eigen::Vector3d w = y.segment<3>(l.angular_velocity(i));
    const double kinetic = 0.5 * b.mass * y.segment<3>(l.velocity(i)).squaredNorm() + 0.5 * w.dot(inertia_matrix(b.inertia) * w);
    out.insert(out.end(), {kinetic, -b.mass * g.dot(y.segment<3>(l.position(i)))});
  }
}

// A row of a series with one item per body or joint, written as it is made, slab by slab:
// fill(first, last, out) appends items [first, last). A million bodies' row would
// otherwise be held whole (a grid's attachment points alone are 96 MB). The slabs are
// whole chunks (a file with one row per chunk has chunk_samples items per chunk), so that
// none is read back to be completed.
template <class Fill>
void write_row_in_slabs(Series& s, hsize_t row, Fill&& fill) {
  constexpr hsize_t slab = 16 * chunk_samples;
  RowBlock b = row_block(s, row, 1);
  const h5::Handle file_space = extend(s, b);  // once for the row
  const hsize_t items = s.item[0];
  for (hsize_t first = 0; first < items; first += slab) {
    b.start[1] = first;
    b.count[1] = std::min(slab, items - first);
    s.buffer.clear();
    fill(first, first + b.count[1], s.buffer);
    write_block(s, file_space, b, s.buffer.data());
  }
  s.buffer.clear();
}

}  // namespace

struct Hdf5Sink::File {
  WriterLock lock;  // first: released after the file is closed
  h5::Handle file;
  Series time;
  std::vector<std::pair<std::size_t, Series>> bodies;  // (index into body_fields, series)
  std::optional<Series> energy, body_energy, joint_force, motor_effort, attachment;
  std::optional<Series> section_force;  // the beams' elements, with the joint forces
  std::optional<Series> modal;          // the flexible bodies' modal coordinates
  std::vector<int> element_joints;      // per beam element (beams in order), its bushing
  hsize_t rows_per_chunk = 1;
  std::vector<double> times;  // every time written, for the XDMF sidecar
};

std::string xdmf_path(const std::string& h5) {
  const auto dot = h5.find_last_of('.');
  const auto slash = h5.find_last_of('/');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return (has_ext ? h5.substr(0, dot) : h5) + ".xdmf";
}

Hdf5Sink::Hdf5Sink(std::string path, FieldSet fields, RunInfo info)
    : path_(std::move(path)), fields_(fields), info_(std::move(info)) {}

// A file prepared for a run that never began (its set-up failed) is not left behind.
Hdf5Sink::~Hdf5Sink() {
  if (!created_) return;
  created_.reset();
  std::remove(part_path().c_str());
}

// The file's series: made in a new file, or opened in a file being resumed.
void Hdf5Sink::lay_out(File& f, const MultibodySystem& system, bool make) {
  const Model& m = system.model();
  const auto n = static_cast<hsize_t>(m.bodies.size()), joints = static_cast<hsize_t>(m.joints.size());
  // Time rows per chunk: up to 16, fewer for very large models so the buffer stays bounded;
  // few rows also keep short what is left to write when a run ends.
  const std::size_t row_bytes = static_cast<std::size_t>(system.dimension() + 6 * static_cast<Eigen::Index>(joints) + 4) * 8;
  f.rows_per_chunk = std::clamp<hsize_t>(buffer_bytes / std::max<std::size_t>(row_bytes, 1), 1, 16);
  const hsize_t rows = f.rows_per_chunk;
  const hid_t file = f.file.get();
  auto series = [&](const std::string& path, std::vector<hsize_t> item, hsize_t chunk_rows, const char* unit) {
    return make ? make_series(file, path, std::move(item), chunk_rows, unit) : open_series(file, path, std::move(item));
  };
  f.time = series("/time", {}, 1024, time_unit);
  for (std::size_t i = 0; i < body_fields.size(); ++i)
    if (fields_.body[i])
      f.bodies.emplace_back(i, series(body_fields[i].dataset, {n, static_cast<hsize_t>(body_fields[i].components)}, rows,
                                      body_fields[i].unit));
  if (fields_.energy) f.energy = series(energy_dataset, {3}, 1024, energy_unit);
  if (fields_.energy) f.body_energy = series(body_energy_dataset, {n, 2}, rows, energy_unit);
  if (fields_.joint_force && joints > 0) f.joint_force = series(joint_force_dataset, {joints, 6}, rows, joint_force_unit);
  const bool motors = std::any_of(m.joints.begin(), m.joints.end(), [](const Joint& j) { return j.motor->kind != JointMotor::Kind::none; });
  if (f.joint_force && motors) f.motor_effort = series(motor_effort_dataset, {joints, 1}, rows, motor_effort_unit);
  if (fields_.body[0] && joints > 0) f.attachment = series(joint_attachment_dataset, {joints, 6}, rows, joint_attachment_unit);
  f.element_joints.clear();
  for (const BeamRecord& b : m.beams)
    for (int e = 0; e < b.elements; ++e) f.element_joints.push_back(b.first_joint + e);
  if (f.joint_force && !f.element_joints.empty())
    f.section_force = series(beam_section_force_dataset, {f.element_joints.size(), 6}, rows, beam_section_force_unit);
  if (fields_.body[0] && !m.flexible.empty())
    f.modal = series(modal_coordinates_dataset, {static_cast<hsize_t>(system.layout().extra / 2)}, 1024, modal_coordinates_unit);
}

// The file under its .part name, locked, with the model's text and the run's settings
// written (and the text let go).
std::unique_ptr<Hdf5Sink::File> Hdf5Sink::create() {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors become exceptions, not stack dumps
  auto f = std::make_unique<File>();
  // The file is made under another name and renamed when its layout is on disk: the path
  // holds either what was there or a readable file, never a half-made one. A file that
  // another run is writing (locked) is neither truncated nor replaced.
  WriterLock::check_free(path_);
  const std::string making = part_path();
  f->lock = WriterLock(making);  // before H5Fcreate, which truncates
  try {
    write_header(*f, making);
  } catch (...) {
    f.reset();
    std::remove(making.c_str());  // ours since the lock was taken: no stray .part
    throw;
  }
  return f;
}

// The new file's model text and run settings.
void Hdf5Sink::write_header(File& file, const std::string& making) {
  File* f = &file;
  // File format 1.10: dense attribute storage, so that large model texts fit as
  // attributes, and single-writer/multiple-reader access (SWMR).
  const h5::Handle fapl = file_access();
  f->file = h5::Handle(H5Fcreate(making.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose,
                       "create the results file " + making);
  const hid_t root = f->file.get();
  h5::write_string_attribute(root, "mbsflow_version", MBSFLOW_VERSION);
  h5::write_text_dataset(root, "model", info_.model_json);
  std::string().swap(info_.model_json);  // on disk now; a million-body model's text is half a gigabyte
  h5::write_string_attribute(root, "method", info_.method);
  h5::write_number_attribute(root, "step", info_.step);
  h5::write_number_attribute(root, "t_start", info_.t_start);
  h5::write_number_attribute(root, "t_end", info_.t_end);
  h5::write_number_attribute(root, "output_every", info_.output_every);
  if (info_.output_interval > 0.0) h5::write_number_attribute(root, "output_interval", info_.output_interval);
  h5::write_string_attribute(root, "command_line", info_.command_line);
  h5::write_string_attribute(root, "fields", fields_text(fields_));
}

void Hdf5Sink::prepare() {
  if (!created_) created_ = create();
}

void Hdf5Sink::begin(const MultibodySystem& system) {
  system_ = &system;
  std::unique_ptr<File> f = created_ ? std::move(created_) : create();
  try {
    lay_out_and_publish(std::move(f), system);
  } catch (...) {
    std::remove(part_path().c_str());  // no stray .part: the path keeps what it held
    throw;
  }
}

void Hdf5Sink::lay_out_and_publish(std::unique_ptr<File> f, const MultibodySystem& system) {
  const Model& m = system.model();
  lay_out(*f, system, true);
  std::vector<std::string> names;
  for (const Body& b : m.bodies) names.push_back(b.name);
  const h5::Handle bodies(H5Gopen2(f->file.get(), "/bodies", H5P_DEFAULT), H5Gclose, "open /bodies");
  h5::write_names(bodies.get(), "names", names);
  if (f->joint_force || f->attachment) {
    names.clear();
    for (const Joint& j : m.joints) names.push_back(j.name);
    const h5::Handle group(H5Gopen2(f->file.get(), "/joints", H5P_DEFAULT), H5Gclose, "open /joints");
    h5::write_names(group.get(), "names", names);
  }
  if (f->modal) {
    names.clear();
    std::vector<int> modes;
    for (const FlexibleBody& b : m.flexible) {
      names.push_back(b.name);
      modes.push_back(b.data->modes());
    }
    const h5::Handle group(H5Gopen2(f->file.get(), "/flexible", H5P_DEFAULT), H5Gclose, "open /flexible");
    h5::write_names(group.get(), "names", names);
    h5::write_array(group.get(), "modes", H5T_NATIVE_INT, modes, {modes.size()});
  }
  const hid_t root = f->file.get();
  identity_ = id_text(random_id());
  h5::write_string_attribute(root, "run_id", identity_);
  h5::write_string_attribute(root, "model_name", m.name);
  // The layout on disk now: a run killed before its first rows leaves a readable file.
  h5::check(H5Fflush(root, H5F_SCOPE_GLOBAL), "flush " + path_);
  // From here on readers may open the file while it grows (HDF5 SWMR); nothing is created
  // in it until end() has closed and opened it again. In SWMR mode before it is renamed
  // into place: a file killed in another mode is marked open for writing, which only
  // h5clear undoes, and the path would hold a file that no reader opens.
  h5::check(H5Fstart_swmr_write(root), "let readers in while the run writes " + path_);
  if (std::rename(part_path().c_str(), path_.c_str()) != 0)
    throw InputError("cannot rename " + part_path() + " to " + path_ + ": " + std::strerror(errno));
  last_flush_ = now_seconds();
  file_ = std::move(f);
}

void Hdf5Sink::resume(const MultibodySystem& system, long snapshots, const std::string& identity) {
  system_ = &system;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (!std::filesystem::exists(path_))
    throw InputError("the results file " + path_ + " is gone: the checkpoint goes on from the snapshots it holds");
  auto f = std::make_unique<File>();
  f->lock = WriterLock(path_);  // refused while another run writes it
  grow_to_stored_end(path_);    // a writer killed while closing the file: see killed_writer.hpp
  // A run killed while in SWMR mode leaves the file marked as open for writing, which
  // HDF5 refuses to open again for writing; the marks are cleared as `h5clear -s` does
  // (the library's own file access property for it).
  const h5::Handle fapl = file_access();
  h5::ignore_status_flags(fapl.get());
  f->file = h5::Handle(H5Fopen(path_.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose,
                       "open the results file " + path_ + " (if a killed run left it marked open, h5clear -s clears the mark)");
  const std::optional<std::string> id = h5::read_string_attribute(f->file.get(), "run_id");
  if (id != identity)
    throw InputError(path_ + " is not the results file of the run this checkpoint was taken from (another run wrote it since)");
  const std::optional<std::string> fields = h5::read_string_attribute(f->file.get(), "fields");
  if (fields != fields_text(fields_))
    throw InputError(path_ + " holds the fields '" + fields.value_or("") + "', the run writes '" + fields_text(fields_) + "'");
  lay_out(*f, system, false);
  // The rows after the checkpoint's are dropped: the resumed run writes them again. The
  // time series goes last in every flush, so its length bounds the others'.
  const hsize_t kept = static_cast<hsize_t>(snapshots), there = rows_of(f->time);
  if (there < kept)
    throw InputError(path_ + " holds " + std::to_string(there) + " snapshots, fewer than the " + std::to_string(snapshots) +
                     " that the checkpoint was taken after");
  truncate(f->time, kept);
  for (auto& [i, series] : f->bodies) truncate(series, kept);
  if (f->energy) truncate(*f->energy, kept);
  if (f->joint_force) truncate(*f->joint_force, kept);
  if (f->motor_effort) truncate(*f->motor_effort, kept);
  if (f->attachment) truncate(*f->attachment, kept);
  if (f->section_force) truncate(*f->section_force, kept);
  if (f->body_energy) truncate(*f->body_energy, kept);
  if (f->modal) truncate(*f->modal, kept);
  f->times = read_rows(f->time, kept);
  h5::check(H5Fflush(f->file.get(), H5F_SCOPE_GLOBAL), "flush " + path_);
  h5::check(H5Fstart_swmr_write(f->file.get()), "let readers in while the run writes " + path_);
  identity_ = identity;
  rows_written_ = snapshots;
  last_flush_ = now_seconds();
  file_ = std::move(f);
}

void Hdf5Sink::sync() {
  if (file_) flush();
}

void Hdf5Sink::write(Snapshot&& s) {
  File& f = *file_;
  const StateLayout& l = system_->layout();
  const Model& m = system_->model();
  // A series with an item per body or joint: buffered until its chunk row is full, or, with
  // one row per chunk (large models), written at once in slabs. Each row lands before
  // flush() appends its time.
  const auto row = static_cast<hsize_t>(rows_written_) + f.time.buffer.size();
  auto put = [&](Series& series, auto fill) {
    if (f.rows_per_chunk == 1)
      write_row_in_slabs(series, row, fill);
    else
      fill(hsize_t{0}, series.item[0], series.buffer);
  };
  auto copy = [](const double* from, std::size_t per_item) {
    return [=](hsize_t first, hsize_t last, std::vector<double>& out) {
      out.insert(out.end(), from + first * per_item, from + last * per_item);
    };
  };
  f.time.buffer.push_back(s.t);
  f.times.push_back(s.t);
  for (auto& [i, series] : f.bodies) {
    const BodyField& field = body_fields[i];
    put(series, [&](hsize_t first, hsize_t last, std::vector<double>& out) {
      for (auto b = static_cast<Eigen::Index>(first); b < static_cast<Eigen::Index>(last); ++b) {
        const double* p = s.state.data() + (l.*field.offset)(b);
        out.insert(out.end(), p, p + field.components);
      }
    });
  }
  if (f.energy) {
    const Energy e = s.energy.value_or(Energy{});
    f.energy->buffer.insert(f.energy->buffer.end(), {e.kinetic, e.gravity, e.elastic});
  }
  if (f.body_energy)
    put(*f.body_energy, [&](hsize_t first, hsize_t last, std::vector<double>& out) {
      append_body_energies(m, l, s.state, static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(last), out);
    });
  if (f.joint_force) put(*f.joint_force, copy(s.joint_wrench.data(), 6));
  if (f.motor_effort) put(*f.motor_effort, copy(s.motor_effort.data(), 1));
  if (f.attachment)
    put(*f.attachment, [&](hsize_t first, hsize_t last, std::vector<double>& out) {
      append_attachment_points(m, l, s.state, first, last, out);
    });
  if (f.section_force)
    put(*f.section_force, [&](hsize_t first, hsize_t last, std::vector<double>& out) {
      append_section_forces(m, l, s.state, s.joint_wrench, f.element_joints, first, last, out);
    });
  if (f.modal)  // each flexible body's eta, the first half of its part of the state's tail
    for (std::size_t b = 0; b < m.flexible.size(); ++b) {
      const double* eta = s.state.data() + system_->flexible_state(b);
      f.modal->buffer.insert(f.modal->buffer.end(), eta, eta + m.flexible[b].data->modes());
    }
  if (static_cast<hsize_t>(f.time.buffer.size()) >= f.rows_per_chunk || now_seconds() - last_flush_ >= flush_interval_s)
    flush();
}

void Hdf5Sink::flush() {
  File& f = *file_;
  const auto first = static_cast<hsize_t>(rows_written_);
  const long rows = static_cast<long>(f.time.buffer.size());
  if (rows == 0) return;
  // Every data series on disk, rows and extent, before the time series grows: the library
  // writes a dataset's metadata to the file whenever it evicts it, and one H5Fflush orders
  // nothing between datasets, so a live reader could see times before the rows they stand
  // for. Hence two file flushes. (H5Dflush per series, tried, failed now and then in a
  // run resumed from a killed one's file: 1 in 12 kill -9 and --resume cycles here.)
  for (auto& [i, series] : f.bodies) append(series, first);
  if (f.energy) append(*f.energy, first);
  if (f.body_energy) append(*f.body_energy, first);
  if (f.joint_force) append(*f.joint_force, first);
  if (f.motor_effort) append(*f.motor_effort, first);
  if (f.attachment) append(*f.attachment, first);
  if (f.section_force) append(*f.section_force, first);
  if (f.modal) append(*f.modal, first);
  h5::check(H5Fflush(f.file.get(), H5F_SCOPE_GLOBAL), "flush " + path_);
  append(f.time, first);  // last: a reader never sees a time without its data
  rows_written_ += rows;
  h5::check(H5Fflush(f.file.get(), H5F_SCOPE_GLOBAL), "flush " + path_);
  last_flush_ = now_seconds();
}

void Hdf5Sink::write_coupling(const std::vector<CouplingRecord>& records) {
  coupling_ = records;  // written by end(): a file being read live gets no new datasets
}

void Hdf5Sink::end() {
  if (!file_) return;
  std::unique_ptr<File> f;
  try {
    flush();
  } catch (...) {
    file_.reset();  // close what can be closed
    throw;
  }
  std::swap(f, file_);
  // Out of SWMR mode, by closing the file, to add what a live reader must not see made:
  // the coupling records and the XDMF sidecar's views. The lock is held until then.
  const WriterLock lock = std::move(f->lock);
  XdmfContent c;
  c.bodies = system_->model().bodies.size();
  c.joints = system_->model().joints.size();
  for (std::size_t i = 0; i < body_fields.size(); ++i)
    if (fields_.body[i]) c.body_fields.push_back(&body_fields[i]);
  c.joint_attachment = f->attachment.has_value();
  c.joint_force = f->joint_force.has_value();
  c.energy = f->energy.has_value();
  c.body_energy = f->body_energy.has_value();
  const std::vector<BeamRecord>& beams = system_->model().beams;
  for (std::size_t b = 0; b < beams.size(); ++b)
    for (int e = 0; e < beams[b].elements; ++e) {
      c.beam_lines.insert(c.beam_lines.end(), {beams[b].first_body + e, beams[b].first_body + e + 1});
      c.beam_index.push_back(static_cast<int>(b));
    }
  c.beam_joint = f->element_joints;  // the elements' bushings, in the same order
  c.beam_section_force = f->section_force.has_value();
  if (f->modal && fields_.body[1]) {  // a flexible body's surface is drawn from its frame's orientation
    std::size_t first = 0;
    for (const FlexibleBody& b : system_->model().flexible) {
      if (b.data->display_position.cols() > 0) c.surfaces.push_back({b.name, b.frame, first, b.data.get()});
      first += static_cast<std::size_t>(b.data->modes());
    }
  }
  const std::vector<double> times = std::move(f->times);
  f.reset();
  const h5::Handle file(H5Fopen(path_.c_str(), H5F_ACC_RDWR, file_access().get()), H5Fclose, "open " + path_ + " again");
  write_coupling_records(file.get(), coupling_);
  if (fields_.body[0]) write_xdmf(file.get(), xdmf_path(path_), path_, times, c);  // the sidecar needs the positions
}

}  // namespace mbsflow
