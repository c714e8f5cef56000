#include "mbsflow/io/output_path.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "hdf5_handle.hpp"
#include "killed_writer.hpp"
#include "writer_lock.hpp"

namespace mbsflow {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

bool same_file(const struct stat& a, const std::string& other) {
  struct stat b {};
  return ::stat(other.c_str(), &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

}  // namespace

bool is_mbsflow_results_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  // The signature first: HDF5 is not asked to open what is plainly no HDF5 file.
  char head[8] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(head, sizeof head) || std::memcmp(head, "\x89HDF\r\n\x1a\n", 8) != 0) return false;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  // Not HDF5's own file lock: a file that a run is writing is told by WriterLock, and a
  // reader must not be refused because a killed run left the lock mark.
  H5Pset_file_locking(fapl, false, true);
  const hid_t file = h5::open_read_only(path, fapl, !WriterLock::held(path));
  H5Pclose(fapl);
  if (file < 0) return false;
  const bool ours = H5Aexists(file, "mbsflow_version") > 0;
  H5Fclose(file);
  return ours;
}

void mend_results_file_to_resume(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) return;
  const WriterLock lock(path);
  grow_to_stored_end(path);
}

void check_output_path(const std::string& path, const OutputPathRules& r) {
  const std::string& flag = r.flag;
  if (path.empty()) throw InputError(flag + ": give a file name (an empty one writes nothing)");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno != ENOENT) throw InputError(flag + " " + path + ": " + std::strerror(errno));
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      throw InputError(flag + " " + path + ": there is no folder " + parent.string() + " to write it in");
    return;  // nothing there yet
  }
  for (const std::string& input : r.inputs)
    if (!input.empty() && same_file(st, input))
      throw InputError(flag + " " + path + " is the input file " + input + ": give the results another name");
  if (!S_ISREG(st.st_mode))
    throw InputError(flag + " " + path + " is " + kind_of(st.st_mode) + ", not a file that results can be written to");
  WriterLock::check_free(path);  // another run writing it says so first
  if (r.force || is_mbsflow_results_file(path)) return;
  throw InputError(flag + " " + path + " exists and is not an mbsflow results file; give another name, or --force to replace it");
}

}  // namespace mbsflow
