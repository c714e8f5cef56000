// libFuzzer target: the cluster file reader.
#include <cstddef>
#include <cstdint>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/io/cluster_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)mbsflow::read_cluster_text(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
  } catch (const mbsflow::Error&) {
  }
  return 0;
}
