#pragma once
// Rewrites an HDF5 file's superblock (versions 2 and 3, 8-byte offsets) as a writer
// killed at a chosen moment leaves it: its file consistency flags and its recorded end of
// file, with the checksum HDF5 checks. For tests only; HDF5 exports the checksum it uses
// for metadata (lookup3) though no public header declares it.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

extern "C" std::uint32_t H5_checksum_metadata(const void* data, std::size_t len, std::uint32_t initval);

namespace mbsflow::test {

struct Superblock {
  unsigned char bytes[48] = {};
  std::uint64_t end() const {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | bytes[28 + i];
    return v;
  }
};

inline Superblock read_superblock(const std::string& path) {
  Superblock s;
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(s.bytes), sizeof s.bytes) || s.bytes[8] < 2 || s.bytes[9] != 8)
    throw std::runtime_error(path + ": no version 2 or 3 superblock");
  std::uint32_t stored = 0;
  std::memcpy(&stored, s.bytes + 44, 4);
  if (stored != H5_checksum_metadata(s.bytes, 44, 0)) throw std::runtime_error(path + ": superblock checksum differs");
  return s;
}

// flags: 0 (closed), 1 (open for writing); end: the end of file address it records.
inline void rewrite_superblock(const std::string& path, unsigned char flags, std::uint64_t end) {
  Superblock s = read_superblock(path);
  s.bytes[11] = flags;
  for (int i = 0; i < 8; ++i) s.bytes[28 + i] = static_cast<unsigned char>(end >> (8 * i));
  const std::uint32_t sum = H5_checksum_metadata(s.bytes, 44, 0);
  std::memcpy(s.bytes + 44, &sum, 4);
  std::fstream io(path, std::ios::binary | std::ios::in | std::ios::out);
  io.write(reinterpret_cast<const char*>(s.bytes), sizeof s.bytes);
  if (!io) throw std::runtime_error(path + ": cannot rewrite the superblock");
}

}  // namespace mbsflow::test
