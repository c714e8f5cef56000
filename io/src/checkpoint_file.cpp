#include "mbsflow/io/checkpoint_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/state_archive.hpp"
#include "mbsflow/version.hpp"

namespace mbsflow {
namespace {

constexpr char magic[16] = {'M', 'B', 'S', 'F', 'L', 'O', 'W', '-', 'C', 'K', 'P', 'T', 0, 0, 0, 1};

std::uint64_t fnv1a(const std::uint8_t* p, std::size_t n) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

[[noreturn]] void io_fail(const std::string& what, const std::string& path) {
  throw InputError("cannot " + what + " " + path + ": " + std::strerror(errno));
}

// Writes all bytes and flushes them to the disk.
void write_synced(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) io_fail("create", path);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      io_fail("write", path);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    io_fail("flush", path);
  }
  if (::close(fd) != 0) io_fail("close", path);
}

// The rename is on disk once the folder is synced.
void sync_folder(const std::string& path) {
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // the rename happened; only its durability is unconfirmed
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void write_checkpoint_file(const std::string& path, const CheckpointFile& c) {
  StateWriter w;
  w.text(MBSFLOW_VERSION);
  w.integer(static_cast<std::int64_t>(c.arguments.size()));
  for (const std::string& a : c.arguments) w.text(a);
  w.text(c.directory);
  w.text(c.model_text);
  w.bytes(c.state);
  const std::vector<std::uint8_t>& payload = w.data();
  std::vector<std::uint8_t> out(magic, magic + sizeof magic);
  out.reserve(out.size() + payload.size() + 16);
  put_u64(out, payload.size());
  out.insert(out.end(), payload.begin(), payload.end());
  put_u64(out, fnv1a(payload.data(), payload.size()));
  const std::string tmp = path + ".tmp";
  write_synced(tmp, out);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) io_fail("rename " + tmp + " to", path);
  sync_folder(path);
}

CheckpointFile read_checkpoint_file(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError("cannot read the checkpoint " + path + ": " + ec.message());
  if (size > max_checkpoint_bytes) throw InputError("the checkpoint " + path + " is larger than any checkpoint (64 GiB)");
  const std::string what = "the checkpoint " + path;
  if (size < sizeof magic + 16) throw InputError(what + " is too short to be a checkpoint");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw InputError("cannot read " + what);
  if (std::memcmp(bytes.data(), magic, 12) != 0) throw InputError(what + " is not an mbsflow checkpoint");
  if (std::memcmp(bytes.data(), magic, sizeof magic) != 0)
    throw InputError(what + " is of another checkpoint format than this mbsflow reads");
  const std::uint64_t length = get_u64(bytes.data() + sizeof magic);
  if (length != bytes.size() - sizeof magic - 16) throw InputError(what + " is cut short or has bytes added (a torn write?)");
  const std::uint8_t* payload = bytes.data() + sizeof magic + 8;
  if (get_u64(payload + length) != fnv1a(payload, static_cast<std::size_t>(length)))
    throw InputError(what + " is damaged: its checksum does not match");
  StateReader r({payload, static_cast<std::size_t>(length)}, what);
  CheckpointFile c;
  c.version = r.text();
  if (c.version != MBSFLOW_VERSION)
    throw InputError(what + " was written by mbsflow " + c.version + "; this is " + MBSFLOW_VERSION +
                     ", whose numbers may differ: resume it with that version");
  const auto n = r.integer(0, 1 << 16);
  for (std::int64_t i = 0; i < n; ++i) c.arguments.push_back(r.text());
  c.directory = r.text();
  c.model_text = r.text();
  c.state = r.bytes();
  if (!r.at_end()) r.fail("bytes after the state");
  return c;
}

}  // namespace mbsflow
