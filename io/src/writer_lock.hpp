#pragma once
// A lock that one run holds on its results file while it writes it: a second run with
// the same -o is refused before it truncates the file (HDF5 truncates before it takes
// its own lock). An open-file-description lock (Linux fcntl F_OFD_SETLK): released when
// the process ends, killed or not, and independent of HDF5's flock on the same file.
#include <string>

namespace mbsflow {

class WriterLock {
 public:
  WriterLock() = default;
  // Creates the file if it is missing (never truncates it) and locks it; InputError if
  // another process holds the lock.
  explicit WriterLock(const std::string& path);
  // Whether another process holds the lock of an existing file at path.
  static bool held(const std::string& path);
  // InputError if another process holds the lock of an existing file at path.
  static void check_free(const std::string& path);
  ~WriterLock();
  WriterLock(WriterLock&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  WriterLock& operator=(WriterLock&& o) noexcept;
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace mbsflow
