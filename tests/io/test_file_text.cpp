// FileText: a regular file is viewed through a mapping, anything else is read; both give
// the file's bytes, and the errors are read_input_file's.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/file_text.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"

using namespace mbsflow;
namespace fs = std::filesystem;

namespace {

fs::path scratch_file(const std::string& name) { return fs::temp_directory_path() / ("mbsflow_ft_" + std::to_string(::getpid()) + "_" + name); }

}  // namespace

TEST_CASE("file text: a regular file's bytes through its mapping, a model read from it as from its text", "[io][file]") {
  ChainParams c;
  c.bodies = 50;
  const std::string json = model_to_json(make_chain(c));
  const fs::path p = scratch_file("chain.json");
  std::ofstream(p, std::ios::binary) << json;
  {
    const FileText f(p.string(), "model file", max_model_bytes);
    CHECK(f.text() == json);
    CHECK(read_model_file(p.string()).bodies.size() == 50);
    CHECK(model_to_json(read_model_file(p.string())) == model_to_json(read_model_text(json, "m")));
  }
  // Empty: nothing to map; read, and the text is empty.
  std::ofstream(p, std::ios::binary | std::ios::trunc).close();
  CHECK(FileText(p.string(), "model file", max_model_bytes).text().empty());
  // Larger than the cap: refused before anything is read, as read_input_file refuses it.
  std::ofstream(p, std::ios::binary) << json;
  CHECK_THROWS_WITH(FileText(p.string(), "model file", 10), Catch::Contains("more than the 10 a model file may have"));
  fs::remove(p);
  CHECK_THROWS_WITH(FileText(p.string(), "model file", max_model_bytes), Catch::Contains("cannot open the model file"));
}

TEST_CASE("file text: a pipe is read to its end and no further than the cap", "[io][file]") {
  const fs::path p = scratch_file("fifo");
  REQUIRE(::mkfifo(p.c_str(), 0600) == 0);
  const std::string text(300000, 'x');
  ::signal(SIGPIPE, SIG_IGN);  // the writer's end when the reader stops at the cap
  for (const std::size_t cap : {max_model_bytes, std::size_t{1000}}) {
    std::thread writer([&] { std::ofstream(p, std::ios::binary) << text; });  // ends when the reader closes
    std::string error;
    std::string_view seen;
    std::optional<FileText> f;
    try {
      f.emplace(p.string(), "model file", cap);
      seen = f->text();
    } catch (const InputError& e) {
      error = e.what();
    }
    writer.join();
    if (cap == max_model_bytes) CHECK(seen == text);
    else CHECK_THAT(error, Catch::Contains("has more than the 1000 bytes a model file may have"));
  }
  fs::remove(p);
}
