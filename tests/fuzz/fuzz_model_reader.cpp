// libFuzzer target: the model reader (JSON text -> checked Model, then the library's
// own check). Any input may be refused with an mbsflow::Error; nothing else may happen.
#include <cstddef>
#include <cstdint>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/io/model_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const mbsflow::Model m = mbsflow::read_model_text(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    mbsflow::check_model(m);  // what the reader accepts, the library accepts
  } catch (const mbsflow::Error&) {
  }
  return 0;
}
