#pragma once
// A checkpoint file (FILE.ckpt): what `mbsflow run --resume FILE` needs to go on with a
// run, bit for bit: the run's command-line arguments and working directory, the model's
// text as it was read, and the run loop's state (mbsflow/runtime/checkpoint.hpp).
//
// Layout: the 16 bytes "MBSFLOW-CKPT\0\0\0\1" (format 1), the payload's length (8 bytes,
// little-endian), the payload (tagged values, mbsflow/methods/state_archive.hpp) and its
// 64-bit FNV-1a hash. Written to FILE.tmp, flushed to disk and renamed over FILE, so a
// crash while writing leaves the previous checkpoint whole; a torn or foreign file is
// refused by its length or hash, never half-read.
#include <cstdint>
#include <string>
#include <vector>

namespace mbsflow {

struct CheckpointFile {
  std::string version;                 // of the mbsflow that wrote it
  std::vector<std::string> arguments;  // after "run", as given
  std::string directory;               // the working directory the arguments' paths are relative to
  std::string model_text;              // the model file as read
  std::vector<std::uint8_t> state;     // the run's (Checkpointing::write)
};

// Largest checkpoint file read (the state of a 10-million-body model fits many times).
inline constexpr std::uintmax_t max_checkpoint_bytes = std::uintmax_t{64} << 30;

void write_checkpoint_file(const std::string& path, const CheckpointFile& c);
// InputError naming the file for a missing, damaged, foreign or other-version file.
CheckpointFile read_checkpoint_file(const std::string& path);

}  // namespace mbsflow
