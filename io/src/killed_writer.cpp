#include "killed_writer.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

std::uint64_t little_endian_u64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

bool grow_to_stored_end(const std::string& path) {
  // Superblock versions 2 and 3: signature (8 bytes), version, sizes of offsets and of
  // lengths, file consistency flags, then the base address, the superblock extension's
  // address and the end-of-file address (8 bytes each with 8-byte offsets).
  unsigned char head[36] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(head), sizeof head)) return false;
  if (std::memcmp(head, "\x89HDF\r\n\x1a\n", 8) != 0 || head[8] < 2 || head[8] > 3 || head[9] != 8) return false;
  if (head[11] == 0) return false;  // closed cleanly: a short file is not the killed writer's
  const std::uint64_t end = little_endian_u64(head + 12) + little_endian_u64(head + 28);
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size >= end) return false;
  if (::truncate(path.c_str(), static_cast<off_t>(end)) != 0)
    throw InputError("cannot grow " + path + " to the end its killed writer recorded: " + std::strerror(errno));
  return true;
}

}  // namespace mbsflow
