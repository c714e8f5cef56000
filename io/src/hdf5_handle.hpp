#pragma once
// Owning handles for HDF5 identifiers and an error check, for io/ only.
#include <hdf5.h>

#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mbsflow/error.hpp"

namespace mbsflow::h5 {

class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer close, const std::string& what) : id_(id), close_(close) {
    if (id < 0) throw Error("HDF5: cannot " + what);
  }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    reset();
    id_ = std::exchange(o.id_, H5I_INVALID_HID);
    close_ = o.close_;
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }
  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = H5I_INVALID_HID;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer close_ = nullptr;
};

inline void check(herr_t status, const std::string& what) {
  if (status < 0) throw Error("HDF5: cannot " + what);
}

// A variable-length UTF-8 string type.
// A file whose writer was killed outside SWMR mode is marked open for writing, and HDF5
// refuses to open it again; this property makes the open ignore (and, read-write, clear)
// the mark, as `h5clear -s` does.
inline void ignore_status_flags(hid_t fapl) {
  hbool_t clear = 1;
  if (H5Pexist(fapl, "clear_status_flags") > 0) H5Pset(fapl, "clear_status_flags", &clear);
}

// Opens a file read-only: plainly; else as an SWMR reader (a file that a run is writing,
// or one whose writer was killed in SWMR mode); else, where no writer has it any more
// (writer_gone), ignoring the open-for-writing mark that a writer killed outside SWMR
// mode leaves (as `h5clear -s` would, without writing). Negative if none succeeds.
inline hid_t open_read_only(const std::string& path, hid_t fapl, bool writer_gone) {
  hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  if (file < 0) file = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);
  if (file >= 0 || !writer_gone) return file;
  const Handle cleared(fapl == H5P_DEFAULT ? H5Pcreate(H5P_FILE_ACCESS) : H5Pcopy(fapl), H5Pclose,
                       "copy a file access list");
  ignore_status_flags(cleared.get());
  return H5Fopen(path.c_str(), H5F_ACC_RDONLY, cleared.get());
}

inline Handle string_type() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose, "copy the string type");
  check(H5Tset_size(t.get(), H5T_VARIABLE), "size the string type");
  check(H5Tset_cset(t.get(), H5T_CSET_UTF8), "set UTF-8");
  return t;
}

inline void write_string_attribute(hid_t obj, const char* name, const std::string& value) {
  const Handle type = string_type();
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  const Handle attr(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    std::string("create attribute ") + name);
  const char* p = value.c_str();
  check(H5Awrite(attr.get(), type.get(), &p), std::string("write attribute ") + name);
}

// The string attribute `name` of obj; nullopt when it has none.
inline std::optional<std::string> read_string_attribute(hid_t obj, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) <= 0) return std::nullopt;
  const Handle attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, "open attribute " + name);
  const Handle type = string_type();
  char* value = nullptr;
  check(H5Aread(attr.get(), type.get(), &value), "read attribute " + name);
  std::string s = value ? value : "";
  H5free_memory(value);
  return s;
}

// A long text as a scalar dataset of one fixed-length string (contiguous, UTF-8): HDF5
// writes it from the caller's buffer, where an attribute held three copies of a
// million-body model's text (variable length: global heap and conversion; fixed length:
// dense attribute storage).
inline void write_text_dataset(hid_t parent, const char* name, const std::string& value) {
  const Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "copy the string type");
  check(H5Tset_size(type.get(), value.empty() ? 1 : value.size()), "size the string type");
  check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), "pad the string type");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "set UTF-8");
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  const Handle set(H5Dcreate2(parent, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                   std::string("create dataset ") + name);
  const char zero = '\0';
  check(H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, value.empty() ? &zero : value.data()),
        std::string("write dataset ") + name);
}

// What write_text_dataset wrote; nullopt when parent has no such dataset.
inline std::optional<std::string> read_text_dataset(hid_t parent, const std::string& name) {
  if (H5Lexists(parent, name.c_str(), H5P_DEFAULT) <= 0) return std::nullopt;
  const Handle set(H5Dopen2(parent, name.c_str(), H5P_DEFAULT), H5Dclose, "open dataset " + name);
  const Handle type(H5Dget_type(set.get()), H5Tclose, "type of dataset " + name);
  if (H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) != 0)
    throw InputError("dataset " + name + " is not a fixed-length string");
  std::string s(H5Tget_size(type.get()), '\0');
  check(H5Dread(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), "read dataset " + name);
  s.resize(std::strlen(s.c_str()));  // null padded
  return s;
}

// The "units" attribute of a dataset of the file.
inline void write_units(hid_t file, const char* dataset, const char* units) {
  const Handle set(H5Dopen2(file, dataset, H5P_DEFAULT), H5Dclose, std::string("open ") + dataset);
  write_string_attribute(set.get(), "units", units);
}

inline void write_number_attribute(hid_t obj, const char* name, double value) {
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  const Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    std::string("create attribute ") + name);
  check(H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &value), std::string("write attribute ") + name);
}

// A whole dataset of the given shape, written at once (not extendible).
template <class T>
void write_array(hid_t parent, const char* name, hid_t type, const std::vector<T>& data, std::vector<hsize_t> dims) {
  const Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose,
                     std::string("create the space of ") + name);
  const Handle set(H5Dcreate2(parent, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                   std::string("create ") + name);
  if (!data.empty()) check(H5Dwrite(set.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), std::string("write ") + name);
}

// A list of strings as a dataset of variable-length strings.
inline void write_names(hid_t parent, const char* name, const std::vector<std::string>& names) {
  const Handle type = string_type();
  const hsize_t n = names.size();
  const Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose, "create a names space");
  const Handle set(H5Dcreate2(parent, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                   std::string("create ") + name);
  std::vector<const char*> p;
  for (const auto& s : names) p.push_back(s.c_str());
  if (n > 0) check(H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), "write names");
}

}  // namespace mbsflow::h5
