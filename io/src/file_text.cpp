#include "mbsflow/io/file_text.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include "json_node.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/model_reader.hpp"

namespace mbsflow {

FileText::FileText(const std::string& path, const std::string& what, std::size_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    if (fd >= 0) ::close(fd);
    read_ = read_input_file(path, what, max_bytes);  // its error: cannot open
    return;
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw InputError(path + ": is a folder, not a " + what);
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (S_ISREG(st.st_mode) && size > max_bytes) {
    ::close(fd);
    read_ = read_input_file(path, what, max_bytes);  // its error: too large, unread
    return;
  }
  if (S_ISREG(st.st_mode) && size > 0) {
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (p != MAP_FAILED) {
      mapped_ = static_cast<const char*>(p);
      size_ = size;
      ::close(fd);  // a mapping outlives its descriptor
      return;
    }
  }
  // A pipe (read from this descriptor: a fifo opened twice would lose its writer), an empty
  // or unmappable file: read to the end, no more than max_bytes.
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      ::close(fd);
      throw InputError(path + ": cannot read the " + what);
    }
    if (n == 0) break;
    if (read_.size() + static_cast<std::size_t>(n) > max_bytes) {
      ::close(fd);
      throw InputError(path + ": the " + what + " has more than the " + std::to_string(max_bytes) + " bytes a " + what +
                       " may have");
    }
    read_.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
}

FileText::~FileText() {
  if (mapped_) ::munmap(const_cast<char*>(mapped_), size_);
}

FileText map_model_file(const std::string& path) { return FileText(path, "model file", max_model_bytes); }

}  // namespace mbsflow
