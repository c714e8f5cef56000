// libFuzzer target: the partition file reader, against a chain of 6 bodies (the file names
// its model: the corpus does, so the fuzzer reaches the part_of_body checks).
#include <unistd.h>

#include <cstddef>
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
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The reader takes a path: the input goes to a file of this process.
  static const std::string path = "/tmp/mbsflow_fuzz_partition_" + std::to_string(::getpid()) + ".json";
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    (void)mbsflow::read_partition_file(chain(), path);
  } catch (const mbsflow::Error&) {
  }
  return 0;
}
