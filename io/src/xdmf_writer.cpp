#include "xdmf_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

#include "hdf5_handle.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/result_fields.hpp"

namespace mbsflow {
namespace {

constexpr const char* views_group = "/xdmf";
constexpr std::size_t compact_limit_bytes = 32768;  // a compact dataset's data: within HDF5's 64 KiB header
// A view of at most this many values is written into the sidecar as text (shortest
// round-trip digits, which ParaView reads back bit for bit) instead of as a dataset:
// making and closing a dataset costs about 20 us, and a small model's 1000 snapshots of
// five quantities spent 0.12-0.14 s of a 0.33-0.41 s run on them (IFToMM A05, 4 bodies;
// docs/results.md).
constexpr hsize_t inline_view_values = 64;

// A source's items per time row (the dimensions between time and the last).
hsize_t row_items(const Source& source) {
  hsize_t items = 1;
  for (std::size_t d = 1; d + 1 < source.extent.size(); ++d) items *= source.extent[d];
  return items;
}

// Whether a view of `values` values of `source` is written into the sidecar as text.
bool text_view(const Source& source, hsize_t values) { return !source.values.empty() && values <= inline_view_values; }

// Appends columns [column, column + columns) of each item of one time row (`row`: items x
// last, as the series stores it), in the order of the view's array.
void append_columns(std::vector<double>& out, const double* row, hsize_t items, hsize_t last, hsize_t column,
                    hsize_t columns) {
  for (hsize_t k = 0; k < items; ++k) out.insert(out.end(), row + k * last + column, row + k * last + column + columns);
}

// Row `row` of a source that was read (T x item), columns [column, column + columns) of its
// last dimension, in the order of the view's array.
std::vector<double> row_values(const Source& source, hsize_t row, hsize_t column, hsize_t columns) {
  const hsize_t last = source.extent.back(), items = row_items(source);
  std::vector<double> out;
  out.reserve(items * columns);
  append_columns(out, source.values.data() + row * items * last, items, last, column, columns);
  return out;
}

// A copy of row `row` of `source` (T x item), columns [column, column + columns) of its
// last dimension, as a dataset `name` in `group` of shape `dims`: compact (in its object
// header) where it fits.
void make_copy(hid_t group, const char* name, const std::vector<hsize_t>& dims, const h5::Handle& view_space,
               const Source& source, hsize_t row, hsize_t column, hsize_t columns) {
  const std::vector<double> out = row_values(source, row, column, columns);
  hsize_t size = 1;
  for (hsize_t d : dims) size *= d;
  if (size != out.size()) throw Error(std::string("the view ") + name + " does not fit its row");
  const h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create a dataset property list");
  if (out.size() * sizeof(double) <= compact_limit_bytes) h5::check(H5Pset_layout(dcpl.get(), H5D_COMPACT), "make a view compact");
  const h5::Handle set(H5Dcreate2(group, name, H5T_IEEE_F64LE, view_space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                       H5Dclose, std::string("create the view ") + name);
  h5::check(H5Dwrite(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
            std::string("write the view ") + name);
}

void write_ints(hid_t file, const std::string& path, const std::vector<hsize_t>& dims, const std::vector<int>& values) {
  const h5::Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose, "create a space");
  const h5::Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose, "create a link property list");
  h5::check(H5Pset_create_intermediate_group(lcpl.get(), 1), "allow intermediate groups");
  const h5::Handle set(H5Dcreate2(file, path.c_str(), H5T_STD_I32LE, space.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
                       H5Dclose, "create " + path);
  if (!values.empty())
    h5::check(H5Dwrite(set.get(), H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), "write " + path);
}

std::string dims_text(std::size_t a, std::size_t b) { return std::to_string(a) + ' ' + std::to_string(b); }

// The file's user block, from whose end HDF5's addresses count. `file` may be a group.
hsize_t user_block(hid_t file) {
  const h5::Handle holder(H5Iget_file_id(file), H5Fclose, "get the results file");
  const h5::Handle fcpl(H5Fget_create_plist(holder.get()), H5Pclose, "get the file's properties");
  hsize_t base = 0;
  h5::check(H5Pget_userblock(fcpl.get(), &base), "get the file's user block");
  return base;
}

}  // namespace

Source::Source(hid_t file, const char* p, bool whole_rows) : path(p) {
  set = h5::Handle(H5Dopen2(file, p, H5P_DEFAULT), H5Dclose, std::string("open ") + p);
  space = h5::Handle(H5Dget_space(set.get()), H5Sclose, std::string("get the space of ") + p);
  extent.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
  H5Sget_simple_extent_dims(space.get(), extent.data(), nullptr);
  const h5::Handle dcpl(H5Dget_create_plist(set.get()), H5Pclose, std::string("get the properties of ") + p);
  const h5::Handle type(H5Dget_type(set.get()), H5Tclose, std::string("get the type of ") + p);
  std::vector<hsize_t> chunk(extent.size());
  if (!extent.empty() && H5Pget_layout(dcpl.get()) == H5D_CHUNKED && H5Pget_nfilters(dcpl.get()) == 0 &&
      H5Tequal(type.get(), H5T_IEEE_F64LE) > 0 &&
      H5Pget_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()) == static_cast<int>(chunk.size()) &&
      std::equal(chunk.begin() + 1, chunk.end(), extent.begin() + 1)) {
    base_ = user_block(set.get());  // of the dataset's file: `file` may be a group
    chunk_rows_ = chunk[0];
  }
  hsize_t count = 1;
  for (hsize_t e : extent) count *= e;
  if (count == 0 || count * sizeof(double) > xdmf_copy_limit_bytes) return;
  if (whole_rows && chunk_rows_ > 0 && count / extent[0] > inline_view_values) return;  // views read in place
  values.resize(count);
  h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), std::string("read ") + p);
}

std::optional<hsize_t> Source::row_offset(hsize_t row) const {
  if (chunk_rows_ == 0 || row >= extent[0]) return std::nullopt;
  hsize_t row_bytes = sizeof(double);
  for (std::size_t d = 1; d < extent.size(); ++d) row_bytes *= extent[d];
  const hsize_t first = row - row % chunk_rows_;
  if (!chunk_address_ || chunk_at_ != first) {  // the sidecar's rows come in order: one lookup per chunk
    std::vector<hsize_t> at(extent.size(), 0);
    at[0] = first;
    unsigned filters = 0;
    haddr_t address = HADDR_UNDEF;
    hsize_t size = 0;
    if (H5Dget_chunk_info_by_coord(set.get(), at.data(), &filters, &address, &size) < 0 || filters != 0 ||
        size != chunk_rows_ * row_bytes)
      address = HADDR_UNDEF;
    chunk_at_ = first;
    chunk_address_ = address;
  }
  if (*chunk_address_ == HADDR_UNDEF) return std::nullopt;
  return base_ + *chunk_address_ + (row % chunk_rows_) * row_bytes;
}

// A view `name` in `group`, of shape `dims`, of row `row` of `source` (T x item), columns
// [column, column + columns) of its last dimension: a copy where the source was read, else
// a virtual dataset.
void make_view(hid_t group, const char* name, const std::vector<hsize_t>& dims, const Source& source, hsize_t row,
               hsize_t column, hsize_t columns) {
  const h5::Handle view_space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose,
                              "create a view's space");
  if (!source.values.empty()) return make_copy(group, name, dims, view_space, source, row, column, columns);
  std::vector<hsize_t> start(source.extent.size(), 0), count = source.extent;
  start[0] = row;
  count[0] = 1;
  start.back() = column;
  count.back() = columns;
  h5::check(H5Sselect_hyperslab(source.space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
            std::string("select a row of ") + source.path);
  const h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create a dataset property list");
  h5::check(H5Pset_virtual(dcpl.get(), view_space.get(), ".", source.path, source.space.get()),
            std::string("map the view ") + name);
  h5::Handle(H5Dcreate2(group, name, H5T_IEEE_F64LE, view_space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT), H5Dclose,
             std::string("create the view ") + name);
}

// One DataItem reading the dataset `path` of the results file.
void xdmf_item(std::ostream& o, const std::string& file, const std::string& path, const std::string& dims, bool integer,
          const char* indent) {
  o << indent << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"" << (integer ? "Int\" Precision=\"4" : "Float\" Precision=\"8")
    << "\" Format=\"HDF\">" << file << ':' << path << "</DataItem>\n";
}

namespace {

// Views of columns of a series (the bodies' kinetic energies of /bodies/energy, the
// joints' forces of /joints/force) lie nowhere in one piece. Each such quantity is gathered
// once, at the sidecar's rows, into one contiguous dataset /xdmf/columns/<name>, row after
// row, whose rows the sidecar reads in place as binary items: one dataset for the run
// instead of one per snapshot (a copy costs about 20 us to make, a virtual view about 70).
class ColumnTables {
 public:
  struct Column {
    const char* name;
    hsize_t column, columns;  // of the series' last dimension
  };
  // Tables of `columns` of `source` at `rows` (the sidecar's, in its order), each where its
  // views would not be text (StepViews::add) and it fits xdmf_column_limit_bytes.
  void gather(hid_t file, const Source& source, const std::vector<std::size_t>& rows, std::initializer_list<Column> columns) {
    const hsize_t items = row_items(source), last = source.extent.back();
    std::vector<Column> wanted;
    for (const Column& c : columns)
      if (!text_view(source, items * c.columns) && rows.size() * items * c.columns * sizeof(double) <= xdmf_column_limit_bytes)
        wanted.push_back(c);
    if (wanted.empty() || rows.empty()) return;
    std::vector<std::vector<double>> tables(wanted.size());
    for (std::size_t k = 0; k < wanted.size(); ++k) tables[k].reserve(rows.size() * items * wanted[k].columns);
    const hsize_t row_size = items * last;
    std::vector<double> read(source.values.empty() ? row_size : 0);  // a row read from the file, where not held
    std::vector<hsize_t> start(source.extent.size(), 0), count = source.extent;
    count[0] = 1;
    const h5::Handle memory(H5Screate_simple(1, &row_size, nullptr), H5Sclose, "create a row's space");
    for (const std::size_t t : rows) {
      const double* row = read.data();
      if (!source.values.empty()) {
        row = source.values.data() + t * row_size;
      } else {
        start[0] = t;
        h5::check(H5Sselect_hyperslab(source.space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
                  std::string("select a row of ") + source.path);
        h5::check(H5Dread(source.set.get(), H5T_NATIVE_DOUBLE, memory.get(), source.space.get(), H5P_DEFAULT, read.data()),
                  std::string("read a row of ") + source.path);
      }
      for (std::size_t k = 0; k < wanted.size(); ++k) append_columns(tables[k], row, items, last, wanted[k].column, wanted[k].columns);
    }
    const hsize_t base = user_block(file);
    const h5::Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose, "create a link property list");
    h5::check(H5Pset_create_intermediate_group(lcpl.get(), 1), "allow intermediate groups");
    const h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create a dataset property list");
    h5::check(H5Pset_layout(dcpl.get(), H5D_CONTIGUOUS), "make a column table contiguous");
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      const std::string path = std::string(columns_group) + wanted[k].name;
      const std::array<hsize_t, 2> dims{rows.size(), items * wanted[k].columns};
      const h5::Handle space(H5Screate_simple(2, dims.data(), nullptr), H5Sclose, "create a space");
      const h5::Handle set(H5Dcreate2(file, path.c_str(), H5T_IEEE_F64LE, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT),
                           H5Dclose, "create " + path);
      h5::check(H5Dwrite(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, tables[k].data()), "write " + path);
      const haddr_t at = H5Dget_offset(set.get());
      if (at != HADDR_UNDEF) at_[wanted[k].name] = {base + at, dims[1] * sizeof(double)};
    }
  }
  // Where the view `name` of the sidecar's index-th snapshot lies in the file, if gathered.
  std::optional<hsize_t> offset(const std::string& name, std::size_t index) const {
    const auto it = at_.find(name);
    if (it == at_.end()) return std::nullopt;
    return it->second.first + index * it->second.second;
  }

 private:
  static constexpr const char* columns_group = "/xdmf/columns/";
  std::map<std::string, std::pair<hsize_t, hsize_t>> at_;  // the first row's offset, and a row's bytes
};

// An Attribute around the DataItem that item() writes.
template <class Item>
void attribute_around(std::ostream& o, const char* name, const char* type, const char* center, Item item) {
  o << "     <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"" << center << "\">\n";
  item();
  o << "     </Attribute>\n";
}

// The results file's name as the binary DataItems of the `index`-th of `count` snapshots
// of the sidecar give it: "./" or ".//" for each bit of the index, then the name, so that
// no two snapshots name the file alike. ParaView's legacy XDMF reader keeps an array read
// from a binary file while the name stays the same from one time step to the next, whatever
// the Seek (it showed the first step's positions at every step); its default reader does not.
std::string binary_file_name(std::size_t index, std::size_t count, const std::string& name) {
  std::string out;
  for (std::size_t bit = 1; bit < count; bit <<= 1) out += (index & bit) ? ".//" : "./";
  return out + name;
}

// The views of one snapshot: the small ones as text in the sidecar; whole rows stored as
// they are in the results file, and columns gathered into tables, as binary DataItems that
// read them where they lie; the others as datasets in the snapshot's group /xdmf/<row>/,
// made with the first of them.
class StepViews {
 public:
  StepViews(hid_t file, std::string step, std::string binary_file, const ColumnTables& tables, std::size_t index)
      : file_(file), step_(std::move(step)), binary_file_(std::move(binary_file)), tables_(tables), index_(index) {}
  hid_t group() {
    if (!group_) group_ = h5::Handle(H5Gcreate2(file_, step_.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create " + step_);
    return group_->get();
  }
  // View `name` of shape `dims` of row `row` of `source`, columns [column, column + columns) (as make_view).
  void add(const char* name, const std::vector<hsize_t>& dims, const Source& source, hsize_t row, hsize_t column, hsize_t columns) {
    hsize_t size = 1;
    for (hsize_t d : dims) size *= d;
    if (text_view(source, size)) return (void)text_.emplace(name, row_values(source, row, column, columns));
    if (const std::optional<hsize_t> at = tables_.offset(name, index_)) return (void)binary_.emplace(name, *at);
    if (column == 0 && columns == source.extent.back())
      if (const std::optional<hsize_t> at = source.row_offset(row)) return (void)binary_.emplace(name, *at);
    make_view(group(), name, dims, source, row, column, columns);
  }
  // The DataItem of view `name`, and an Attribute holding it.
  void item(std::ostream& o, const std::string& file, const std::string& name, const std::string& dims, const char* indent) const {
    if (const auto at = binary_.find(name); at != binary_.end()) {
      o << indent << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"Float\" Precision=\"8\" Format=\"Binary\" Endian=\"Little\" Seek=\""
        << at->second << "\">" << binary_file_ << "</DataItem>\n";
      return;
    }
    const auto it = text_.find(name);
    if (it == text_.end()) return xdmf_item(o, file, step_ + name, dims, false, indent);
    o << indent << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">";
    // Shortest round-trip digits (std::to_chars): read back bit for bit as %.17g's were, at
    // less cost (a small model's 1000 snapshots hold about 10^5 numbers).
    char number[32 * 8];
    std::size_t used = 0;
    for (std::size_t k = 0; k < it->second.size(); ++k) {
      if (used + 32 > sizeof number) {
        o.write(number, static_cast<std::streamsize>(used));
        used = 0;
      }
      if (k) number[used++] = ' ';
      used = static_cast<std::size_t>(std::to_chars(number + used, number + sizeof number, it->second[k]).ptr - number);
    }
    o.write(number, static_cast<std::streamsize>(used));
    o << "</DataItem>\n";
  }
  void attribute(std::ostream& o, const std::string& file, const char* name, const char* type, const char* center,
                 const std::string& dims) const {
    attribute_around(o, name, type, center, [&] { item(o, file, name, dims, "      "); });
  }

 private:
  hid_t file_;
  std::string step_, binary_file_;
  const ColumnTables& tables_;
  std::size_t index_;  // the snapshot's place in the sidecar
  std::optional<h5::Handle> group_;
  std::map<std::string, std::vector<double>> text_;
  std::map<std::string, hsize_t> binary_;  // a view's byte offset in the results file
};

}  // namespace

void xdmf_attribute(std::ostream& o, const std::string& file, const char* name, const char* type, const char* center,
               const std::string& path, const std::string& dims, bool integer) {
  attribute_around(o, name, type, center, [&] { xdmf_item(o, file, path, dims, integer, "      "); });
}

void write_xdmf(hid_t file, const std::string& xdmf_path, const std::string& h5_path, const std::vector<double>& times,
                const XdmfContent& c) {
  if (H5Lexists(file, views_group, H5P_DEFAULT) > 0)  // a resumed run that had ended before: made again
    h5::check(H5Ldelete(file, views_group, H5P_DEFAULT), "remove the old views");
  const std::string file_name = std::filesystem::path(h5_path).filename().string();  // side by side
  const std::string group = views_group;
  std::vector<int> index(std::max(c.bodies, c.joints));
  for (std::size_t i = 0; i < index.size(); ++i) index[i] = static_cast<int>(i);
  write_ints(file, group + "/body_index", {c.bodies}, {index.begin(), index.begin() + static_cast<long>(c.bodies)});
  const bool lines = c.joint_attachment && c.joints > 0;
  if (lines) {
    std::vector<int> ends(2 * c.joints);
    for (std::size_t i = 0; i < ends.size(); ++i) ends[i] = static_cast<int>(i);
    write_ints(file, group + "/joint_lines", {c.joints, 2}, ends);
    write_ints(file, group + "/joint_index", {c.joints}, {index.begin(), index.begin() + static_cast<long>(c.joints)});
  }

  const std::size_t segments = c.beam_index.size();
  if (segments > 0) {
    write_ints(file, group + "/beam_lines", {segments, 2}, c.beam_lines);
    write_ints(file, group + "/beam_index", {segments}, c.beam_index);
    write_ints(file, group + "/beam_joint", {segments}, c.beam_joint);
  }
  std::vector<Source> body_sources;  // in the order of c.body_fields
  for (const BodyField* f : c.body_fields) body_sources.emplace_back(file, f->dataset, true);
  std::optional<Source> energy, body_energy, ends, wrench;
  if (c.energy) energy.emplace(file, energy_dataset);
  if (c.body_energy) body_energy.emplace(file, body_energy_dataset);
  if (lines) ends.emplace(file, joint_attachment_dataset, true);
  if (lines && c.joint_force) wrench.emplace(file, joint_force_dataset);
  std::optional<Source> section;
  if (segments > 0 && c.beam_section_force) section.emplace(file, beam_section_force_dataset);
  const std::vector<std::size_t> rows = evenly_spread_rows(times.size(), xdmf_max_steps);
  const bool surfaces = !c.surfaces.empty() && surfaces_fit(c.surfaces, rows.size());
  if (surfaces) write_surface_triangles(file, c.surfaces);
  ColumnTables tables;
  if (body_energy) tables.gather(file, *body_energy, rows, {{"kinetic_energy", 0, 1}, {"gravity_energy", 1, 1}});
  if (wrench) tables.gather(file, *wrench, rows, {{"force", 0, 3}, {"torque", 3, 3}});
  if (section) tables.gather(file, *section, rows, {{"section_force", 0, 3}, {"section_moment", 3, 3}});

  std::ofstream o(xdmf_path);
  if (!o) throw Error(xdmf_path + ": cannot write the XDMF sidecar");
  o << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"run\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  char time[32];
  const std::string n3 = dims_text(c.bodies, 3), j3 = dims_text(c.joints, 3);
  for (std::size_t index = 0; index < rows.size(); ++index) {
    const std::size_t t = rows[index];
    const std::string step = group + '/' + std::to_string(t) + '/';
    StepViews views(file, step, binary_file_name(index, rows.size(), file_name), tables, index);
    for (std::size_t i = 0; i < body_sources.size(); ++i) {
      const BodyField* f = c.body_fields[i];
      views.add(f->name, {c.bodies, static_cast<hsize_t>(f->components)}, body_sources[i], t, 0, f->components);
    }
    if (energy) views.add("energy", {3}, *energy, t, 0, 3);
    if (body_energy) {
      views.add("kinetic_energy", {c.bodies}, *body_energy, t, 0, 1);
      views.add("gravity_energy", {c.bodies}, *body_energy, t, 1, 1);
    }
    std::snprintf(time, sizeof time, "%.17g", times[t]);
    o << "   <Grid Name=\"t" << t << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n    <Time Value=\"" << time
      << "\"/>\n    <Grid Name=\"bodies\" GridType=\"Uniform\">\n"
      << "     <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << c.bodies << "\" NodesPerElement=\"1\">\n";
    xdmf_item(o, file_name, group + "/body_index", dims_text(c.bodies, 1), true, "      ");  // Xdmf3 makes no cells without it
    o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
    views.item(o, file_name, "position", n3, "      ");
    o << "     </Geometry>\n";
    for (const BodyField* f : c.body_fields) {
      if (f == &body_fields[0]) continue;  // the geometry
      views.attribute(o, file_name, f->name, f->components == 3 ? "Vector" : "Matrix", "Node",
                      dims_text(c.bodies, static_cast<std::size_t>(f->components)));
    }
    xdmf_attribute(o, file_name, "body_index", "Scalar", "Node", group + "/body_index", std::to_string(c.bodies), true);
    if (body_energy) {
      views.attribute(o, file_name, "kinetic_energy", "Scalar", "Node", std::to_string(c.bodies));
      views.attribute(o, file_name, "gravity_energy", "Scalar", "Node", std::to_string(c.bodies));
    }
    if (c.energy)
      attribute_around(o, "energy_kinetic_gravity_elastic", "Vector", "Grid", [&] { views.item(o, file_name, "energy", "1 3", "      "); });
    o << "    </Grid>\n";
    if (surfaces) write_surfaces_at(file, views.group(), step, t, c.surfaces, o, file_name);
    if (segments > 0) {  // the beams: segments between node bodies, on the bodies' positions
      o << "    <Grid Name=\"beams\" GridType=\"Uniform\">\n"
        << "     <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << segments << "\" NodesPerElement=\"2\">\n";
      xdmf_item(o, file_name, group + "/beam_lines", dims_text(segments, 2), true, "      ");
      o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
      views.item(o, file_name, "position", n3, "      ");
      o << "     </Geometry>\n";
      xdmf_attribute(o, file_name, "beam_index", "Scalar", "Cell", group + "/beam_index", std::to_string(segments), true);
      xdmf_attribute(o, file_name, "joint_index", "Scalar", "Cell", group + "/beam_joint", std::to_string(segments), true);
      if (section) {  // axial and shear forces, torsion and bending moments
        const std::string s3 = dims_text(segments, 3);
        views.add("section_force", {segments, 3}, *section, t, 0, 3);
        views.add("section_moment", {segments, 3}, *section, t, 3, 3);
        views.attribute(o, file_name, "section_force", "Vector", "Cell", s3);
        views.attribute(o, file_name, "section_moment", "Vector", "Cell", s3);
      }
      o << "    </Grid>\n";
    }
    if (lines) {
      views.add("attachment", {2 * c.joints, 3}, *ends, t, 0, 6);
      o << "    <Grid Name=\"joints\" GridType=\"Uniform\">\n"
        << "     <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << c.joints << "\" NodesPerElement=\"2\">\n";
      xdmf_item(o, file_name, group + "/joint_lines", dims_text(c.joints, 2), true, "      ");
      o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
      views.item(o, file_name, "attachment", dims_text(2 * c.joints, 3), "      ");
      o << "     </Geometry>\n";
      if (c.joint_force) {
        views.add("force", {c.joints, 3}, *wrench, t, 0, 3);
        views.add("torque", {c.joints, 3}, *wrench, t, 3, 3);
        views.attribute(o, file_name, "force", "Vector", "Cell", j3);
        views.attribute(o, file_name, "torque", "Vector", "Cell", j3);
      }
      xdmf_attribute(o, file_name, "joint_index", "Scalar", "Cell", group + "/joint_index", std::to_string(c.joints), true);
      o << "    </Grid>\n";
    }
    o << "   </Grid>\n";
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  if (!o) throw Error(xdmf_path + ": error while writing the XDMF sidecar");
}

}  // namespace mbsflow
