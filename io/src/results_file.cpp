#include "mbsflow/io/results_file.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <type_traits>

#include "hdf5_handle.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "writer_lock.hpp"

namespace mbsflow {

static_assert(std::is_same_v<hid_t, std::int64_t>, "hid_t is stored as int64_t");

ResultsFile::ResultsFile(const std::string& path) : path_(path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (!std::filesystem::exists(path)) throw InputError(path + ": no such results file");
  if (H5Fis_hdf5(path.c_str()) <= 0) throw InputError(path + ": not an HDF5 file");
  // A file that a run is writing is in SWMR mode and takes only SWMR readers (as does one
  // whose writer was killed in that mode); one whose writer was killed while writing its
  // end is marked open for writing.
  file_ = h5::open_read_only(path, H5P_DEFAULT, !WriterLock::held(path));
  if (file_ < 0)
    throw InputError(path + ": cannot open the results file (a run that is ending holds it alone for a moment: try again)");
  // Live: open as an SWMR reader. Asked of the open file, not read off which open
  // succeeded: a file this process has open already is handed out as it was first opened,
  // so a plain open can get the live file (which must be refreshed).
  unsigned intent = 0;
  live_ = H5Fget_intent(file_, &intent) >= 0 && (intent & H5F_ACC_SWMR_READ) != 0;
  ode_ = !has("/time") && has("/solution/time");
  modes_ = !has("/time") && has("/modes/frequency");
  if (!has("/time") && !ode_ && !modes_) {
    H5Fclose(file_);
    file_ = -1;
    throw InputError(path + ": not an mbsflow results file (none of /time, /solution/time, /modes/frequency)");
  }
}

ResultsFile::~ResultsFile() {
  if (file_ >= 0) H5Fclose(file_);
}

ResultsFile::ResultsFile(ResultsFile&& o) noexcept
    : path_(std::move(o.path_)), file_(std::exchange(o.file_, -1)), ode_(o.ode_), modes_(o.modes_), live_(o.live_) {}
ResultsFile& ResultsFile::operator=(ResultsFile&& o) noexcept {
  std::swap(path_, o.path_);
  std::swap(file_, o.file_);
  std::swap(ode_, o.ode_);
  std::swap(modes_, o.modes_);
  std::swap(live_, o.live_);
  return *this;
}

bool ResultsFile::has(const std::string& dataset) const {
  // Check each level, since H5Lexists fails on a missing intermediate group.
  std::string sofar;
  std::size_t pos = 1;
  while (pos <= dataset.size()) {
    const std::size_t next = dataset.find('/', pos);
    sofar = dataset.substr(0, next);
    if (H5Lexists(file_, sofar.c_str(), H5P_DEFAULT) <= 0) return false;
    if (next == std::string::npos) break;
    pos = next + 1;
  }
  return true;
}

namespace {

std::vector<hsize_t> extent(const h5::Handle& space) {
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

// In a file a run is writing, refreshed: an SWMR reader sees the rows written since it
// opened the file only after H5Drefresh.
h5::Handle open_dataset(hid_t file, const std::string& dataset, bool live) {
  h5::Handle set(H5Dopen2(file, dataset.c_str(), H5P_DEFAULT), H5Dclose, "open " + dataset);
  if (live) h5::check(H5Drefresh(set.get()), "refresh " + dataset);
  return set;
}

}  // namespace

std::vector<std::uint64_t> ResultsFile::shape(const std::string& dataset) const {
  if (!has(dataset)) return {};
  const h5::Handle set = open_dataset(file_, dataset, live_);
  const h5::Handle space(H5Dget_space(set.get()), H5Sclose, "get the space of " + dataset);
  const std::vector<hsize_t> dims = extent(space);
  return {dims.begin(), dims.end()};
}

std::optional<std::string> ResultsFile::string_attribute(const std::string& name) const {
  return h5::read_string_attribute(file_, name);
}

std::optional<std::string> ResultsFile::model_text() const {
  if (auto text = h5::read_text_dataset(file_, "model")) return text;
  return h5::read_string_attribute(file_, "model");
}

std::optional<std::string> ResultsFile::dataset_string_attribute(const std::string& dataset, const std::string& name) const {
  if (!has(dataset)) return std::nullopt;
  const h5::Handle set(H5Dopen2(file_, dataset.c_str(), H5P_DEFAULT), H5Dclose, "open " + dataset);
  return h5::read_string_attribute(set.get(), name);
}

std::optional<double> ResultsFile::number_attribute(const std::string& name) const {
  if (H5Aexists(file_, name.c_str()) <= 0) return std::nullopt;
  const h5::Handle attr(H5Aopen(file_, name.c_str(), H5P_DEFAULT), H5Aclose, "open attribute " + name);
  double v = 0.0;
  h5::check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v), "read attribute " + name);
  return v;
}

std::vector<double> ResultsFile::read(const std::string& dataset) const {
  if (!has(dataset)) throw InputError(path_ + ": no dataset " + dataset);
  // One handle for the extent and the read: a live file may grow in between two opens.
  const h5::Handle set = open_dataset(file_, dataset, live_);
  const h5::Handle space(H5Dget_space(set.get()), H5Sclose, "get the space of " + dataset);
  std::size_t n = 1;
  for (hsize_t d : extent(space)) n *= d;
  std::vector<double> out(n);
  if (n > 0) h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, space.get(), space.get(), H5P_DEFAULT, out.data()), "read " + dataset);
  return out;
}

namespace {

// The values of `dataset` in the block start .. start + count, row-major.
std::vector<double> read_block(hid_t file, const std::string& dataset, const std::vector<hsize_t>& start,
                               const std::vector<hsize_t>& count) {
  std::size_t n = 1;
  for (hsize_t c : count) n *= c;
  std::vector<double> out(n);
  const h5::Handle set(H5Dopen2(file, dataset.c_str(), H5P_DEFAULT), H5Dclose, "open " + dataset);
  const h5::Handle space(H5Dget_space(set.get()), H5Sclose, "get the space of " + dataset);
  h5::check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), "select in " + dataset);
  const h5::Handle mem(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose, "create a memory space");
  if (n > 0) h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, out.data()), "read " + dataset);
  return out;
}

}  // namespace

std::vector<double> ResultsFile::read_item(const std::string& dataset, std::size_t index) const {
  const std::vector<std::uint64_t> dims = shape(dataset);
  if (dims.size() != 3) throw InputError(path_ + ": " + dataset + " is not a T x N x k dataset");
  if (index >= dims[1]) throw InputError(path_ + ": index " + std::to_string(index) + " out of range in " + dataset);
  return read_block(file_, dataset, {0, index, 0}, {dims[0], 1, dims[2]});
}

std::vector<double> ResultsFile::read_row(const std::string& dataset, std::size_t row) const {
  const std::vector<std::uint64_t> dims = shape(dataset);
  if (dims.empty() || row >= dims[0]) throw InputError(path_ + ": no row " + std::to_string(row) + " in " + dataset);
  std::vector<hsize_t> start(dims.size(), 0), count(dims.begin(), dims.end());
  start[0] = row;
  count[0] = 1;
  return read_block(file_, dataset, start, count);
}

std::vector<double> ResultsFile::time() const { return read(ode_ ? "/solution/time" : "/time"); }

std::vector<std::string> ResultsFile::names(const char* dataset) const {
  if (!has(dataset)) return {};
  const h5::Handle set(H5Dopen2(file_, dataset, H5P_DEFAULT), H5Dclose, std::string("open ") + dataset);
  const std::size_t n = shape(dataset).at(0);
  std::vector<char*> p(n, nullptr);
  const h5::Handle type = h5::string_type();
  if (n > 0) h5::check(H5Dread(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), std::string("read ") + dataset);
  std::vector<std::string> out;
  for (char* s : p) {
    out.emplace_back(s ? s : "");
    H5free_memory(s);
  }
  return out;
}

std::vector<std::string> ResultsFile::body_names() const { return names("/bodies/names"); }
std::vector<std::string> ResultsFile::joint_names() const { return names("/joints/names"); }

std::uintmax_t ResultsFile::size_bytes() const { return std::filesystem::file_size(path_); }

namespace {

// One CSV table: the header, then per time a row of t and, from each block of values
// (T x components, row-major), that time's components; every number to full precision.
struct CsvBlock {
  std::vector<double> values;
  int components = 1;
};

std::string write_csv_table(const std::string& file, const std::string& header, const std::vector<double>& t,
                            const std::vector<CsvBlock>& blocks) {
  std::ofstream out(file);
  if (!out) throw InputError(file + ": cannot write");
  out << header << '\n';
  char buf[32];
  for (std::size_t i = 0; i < t.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g", t[i]);
    out << buf;
    for (const CsvBlock& b : blocks)
      for (int c = 0; c < b.components; ++c) {
        std::snprintf(buf, sizeof buf, ",%.17g", b.values[i * static_cast<std::size_t>(b.components) + static_cast<std::size_t>(c)]);
        out << buf;
      }
    out << '\n';
  }
  if (!out) throw InputError(file + ": error while writing");
  return file;
}

}  // namespace

namespace {

std::string in_dir(const std::string& dir, const std::string& file) { return (std::filesystem::path(dir) / file).string(); }

// solution.csv and steps.csv of an ODE run.
std::vector<std::string> export_ode_csv(const ResultsFile& r, const std::string& dir) {
  std::vector<std::string> written;
  const std::vector<double> t = r.time();
  const std::vector<std::uint64_t> shape = r.shape("/solution/values");
  const std::vector<double> components = r.read("/solution/components");
  std::string header = "t";
  for (double c : components) header += ",y" + std::to_string(static_cast<long>(c) + 1);
  std::vector<CsvBlock> blocks{{r.read("/solution/values"), static_cast<int>(shape.size() == 2 ? shape[1] : 0)}};
  if (r.has("/solution/error")) {
    header += ",error";
    blocks.push_back({r.read("/solution/error"), 1});
  }
  written.push_back(write_csv_table(in_dir(dir, "solution.csv"), header, t, blocks));
  header = "t";
  blocks.clear();
  for (const char* column : {"tau", "taken", "error", "iterations_s", "iterations_s1", "iteration_failed"}) {
    const std::string path = std::string("/steps/") + column;
    if (!r.has(path)) continue;
    header += std::string(",") + column;
    blocks.push_back({r.read(path), 1});
  }
  written.push_back(write_csv_table(in_dir(dir, "steps.csv"), header, r.read("/steps/t"), blocks));
  return written;
}

std::string with_unit(const std::string& column, const char* unit) { return column + " [" + unit + "]"; }

// The bodies named in `wanted` (all where it is empty), as indices into `names`.
std::vector<std::size_t> chosen_bodies(const ResultsFile& r, const std::vector<std::string>& names,
                                       const std::vector<std::string>& wanted) {
  std::vector<std::size_t> bodies;
  if (wanted.empty()) {
    for (std::size_t i = 0; i < names.size(); ++i) bodies.push_back(i);
  } else {
    for (const std::string& w : wanted) {
      const auto it = std::find(names.begin(), names.end(), w);
      if (it == names.end()) throw InputError("{bodies}: no body '" + w + "' in " + r.path());
      bodies.push_back(static_cast<std::size_t>(it - names.begin()));
    }
  }
  return bodies;
}

// modes.csv (a row per mode) and per body BODY.csv: its part of each mode's shape (real
// and imaginary) and its share of the mode's kinetic and strain energy.
std::vector<std::string> export_modes_csv(const ResultsFile& r, const std::string& dir, const std::vector<std::string>& wanted) {
  const std::vector<std::string> names = r.body_names();
  const std::vector<std::size_t> bodies = chosen_bodies(r, names, wanted);
  std::filesystem::create_directories(dir);
  const std::vector<double> frequency = r.read("/modes/frequency");
  std::vector<double> mode(frequency.size());
  for (std::size_t k = 0; k < mode.size(); ++k) mode[k] = static_cast<double>(k + 1);
  std::vector<std::string> written;
  if (wanted.empty())
    written.push_back(write_csv_table(in_dir(dir, "modes.csv"),
                                      "mode,frequency [Hz],damping_ratio,eigenvalue_real [1/s],eigenvalue_imag [1/s],"
                                      "rigid_body,residual",
                                      mode,
                                      {{frequency, 1},
                                       {r.read("/modes/damping_ratio"), 1},
                                       {r.read("/modes/eigenvalue"), 2},
                                       {r.read("/modes/rigid_body"), 1},
                                       {r.read("/modes/residual"), 1}}));
  for (std::size_t b : bodies)
    written.push_back(write_csv_table(
        in_dir(dir, names[b] + ".csv"),
        "mode,x,y,z,rx,ry,rz,x_imag,y_imag,z_imag,rx_imag,ry_imag,rz_imag,kinetic_share,strain_share", mode,
        {{r.read_item("/modes/shape", b), 6}, {r.read_item("/modes/shape_imag", b), 6}, {r.read_item("/modes/energy_share", b), 2}}));
  return written;
}

}  // namespace

std::vector<std::string> export_csv(const ResultsFile& r, const std::string& dir, const std::vector<std::string>& wanted) {
  if (r.ode()) {
    if (!wanted.empty()) throw InputError("{bodies}: " + r.path() + " holds the solution of an ODE, not bodies");
    std::filesystem::create_directories(dir);
    return export_ode_csv(r, dir);
  }
  if (r.modes()) return export_modes_csv(r, dir, wanted);
  const std::vector<std::string> names = r.body_names();
  const std::vector<std::size_t> bodies = chosen_bodies(r, names, wanted);
  std::filesystem::create_directories(dir);
  const std::vector<double> t = r.time();
  const std::string time_column = with_unit("t", time_unit);
  std::vector<const BodyField*> fields;
  for (const BodyField& f : body_fields)
    if (r.has(f.dataset)) fields.push_back(&f);
  const bool body_energies = r.has(body_energy_dataset);
  std::vector<std::string> written;
  for (std::size_t b : bodies) {
    std::string header = time_column;
    std::vector<CsvBlock> blocks;
    for (const BodyField* f : fields) {
      for (int c = 0; c < f->components; ++c) header += "," + with_unit(f->columns[static_cast<std::size_t>(c)], f->unit);
      blocks.push_back({r.read_item(f->dataset, b), f->components});
    }
    if (body_energies) {
      header += ",kinetic_energy [J],gravity_energy [J]";
      blocks.push_back({r.read_item(body_energy_dataset, b), 2});
    }
    written.push_back(write_csv_table(in_dir(dir, names[b] + ".csv"), header, t, blocks));
  }
  if (!wanted.empty()) return written;
  if (r.has(energy_dataset))
    written.push_back(write_csv_table(in_dir(dir, "energy.csv"),
                                      time_column + ",kinetic [J],gravity [J],elastic [J]", t, {{r.read(energy_dataset), 3}}));
  const std::vector<std::string> joints = r.joint_names();
  const bool force = r.has(joint_force_dataset), effort = r.has(motor_effort_dataset), ends = r.has(joint_attachment_dataset);
  if (!force && !ends) return written;
  for (std::size_t j = 0; j < joints.size(); ++j) {  // joint_NAME.csv
    std::string header = time_column;
    std::vector<CsvBlock> blocks;
    if (force) {
      header += ",fx [N],fy [N],fz [N],mx [N m],my [N m],mz [N m]";
      blocks.push_back({r.read_item(joint_force_dataset, j), 6});
    }
    if (effort) {
      header += ",motor_effort [N m or N]";
      blocks.push_back({r.read_item(motor_effort_dataset, j), 1});
    }
    if (ends) {
      header += ",x1 [m],y1 [m],z1 [m],x2 [m],y2 [m],z2 [m]";
      blocks.push_back({r.read_item(joint_attachment_dataset, j), 6});
    }
    written.push_back(write_csv_table(in_dir(dir, "joint_" + joints[j] + ".csv"), header, t, blocks));
  }
  return written;
}

}  // namespace mbsflow
