#include "writer_lock.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "mbsflow/error.hpp"

namespace mbsflow {

WriterLock::WriterLock(const std::string& path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError("cannot create the results file " + path + ": " + std::strerror(errno));
  struct flock l {};
  l.l_type = F_WRLCK;
  l.l_whence = SEEK_SET;  // the whole file (l_start = l_len = 0)
  if (::fcntl(fd_, F_OFD_SETLK, &l) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    if (e == EAGAIN || e == EACCES)
      throw InputError("another run is writing the results file " + path + "; give another -o, or wait for it to end");
    throw InputError("cannot lock the results file " + path + ": " + std::strerror(e));
  }
}

bool WriterLock::held(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;  // no file: nobody writes it
  struct flock l {};
  l.l_type = F_WRLCK;
  l.l_whence = SEEK_SET;
  const int got = ::fcntl(fd, F_OFD_GETLK, &l);
  ::close(fd);
  return got == 0 && l.l_type != F_UNLCK;
}

void WriterLock::check_free(const std::string& path) {
  if (held(path))
    throw InputError("another run is writing the results file " + path + "; give another -o, or wait for it to end");
}

WriterLock::~WriterLock() {
  if (fd_ >= 0) ::close(fd_);
}

WriterLock& WriterLock::operator=(WriterLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

}  // namespace mbsflow
