// libFuzzer target: the partition file reader, against a chain of 6 bodies (the file names
// its model: the corpus does, so the fuzzer reaches the part_of_body checks).
#include <unistd.h>

#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <fstream>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/partition_file.hpp"

namespace {
const mbsflow::Model& chain() {
  static const mbsflow::Model m = [] {
    mbsflow::ChainParams p;
    p.bodies = 6;
    return mbsflow::make_chain(p);
  }();
  return m;
}

// A file of this process, removed when it exits.
struct ProcessFile {
  std::string path = "/tmp/mbsflow_fuzz_partition_" + std::to_string(::getpid()) + ".json";
  ~ProcessFile() { std::remove(path.c_str()); }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The reader takes a path: the input goes to a file of this process.
  static const ProcessFile file;
  std::ofstream(file.path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    (void)mbsflow::read_partition_file(chain(), file.path);
  } catch (const mbsflow::Error&) {
  }
  return 0;
}
