// Inputs an unlucky user or an attacker could give (the findings of issue 21, replayed):
// each is an InputError naming the field, found before any value is converted or any
// loop bound by it runs.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/cluster_file.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/partition_file.hpp"
#include "mbsflow/methods/step_grid.hpp"

using namespace mbsflow;

namespace {

std::string cluster_with(const std::string& workers_extra, const std::string& timeouts = "") {
  return R"({"coordinator": {"bind": "tcp://127.0.0.1:7000"}, )" + timeouts +
         R"("workers": [{"address": "tcp://127.0.0.1:7001", "data_bind": "tcp://127.0.0.1:7002")" + workers_extra + "}]}";
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / ("mbsflow_limits_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST_CASE("deeply nested JSON is refused before it is parsed, in little time", "[io][limits]") {
  const std::string deep = std::string(50000, '[') + std::string(50000, ']');  // 100 KB
  const auto start = std::chrono::steady_clock::now();
  CHECK_THAT(error_of([&] { read_model_text(deep, "deep.json"); }), Catch::Contains("deep.json:1:65: nested deeper than 64"));
  CHECK_THAT(error_of([&] { read_cluster_text(deep, "deep.json"); }), Catch::Contains("nested deeper than 64"));
  // Had taken 28 s and 6 GB; a scan of 100 KB takes microseconds (one second is the
  // bound of a machine that is very busy, not a speed claim).
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 1.0);
  // Brackets inside strings are text, not nesting.
  CHECK(error_of([] { read_model_text(R"({"name": ")" + std::string(100, '[') + R"("})", "s.json"); }).find("nested") ==
        std::string::npos);
}

TEST_CASE("cluster numbers are range-checked before conversion", "[io][limits]") {
  CHECK_THAT(error_of([] { read_cluster_text(cluster_with(R"(, "weight": 4294967297)"), "c.json"); }),
             Catch::Contains("workers[0].weight: must be <= 1000000 (got 4294967297)"));
  CHECK_THAT(error_of([] { read_cluster_text(cluster_with(R"(, "submodels": [4294967297])"), "c.json"); }),
             Catch::Contains("must be <= 2147483647"));
  CHECK_THAT(error_of([] { read_cluster_text(cluster_with("", R"("timeouts": {"heartbeat_s": 1e300, "lost_s": 1e301}, )"), "c.json"); }),
             Catch::Contains("heartbeat_s must be at most 30 s"));
  CHECK_THAT(error_of([] { read_cluster_text(cluster_with("", R"("timeouts": {"lost_s": 1e300}, )"), "c.json"); }),
             Catch::Contains("lost_s must be at most 600 s"));
  CHECK(read_cluster_text(cluster_with(R"(, "weight": 3)"), "c.json").workers[0].weight == 3);
}

TEST_CASE("a partition file's numbers are integers in range", "[io][limits]") {
  ChainParams chain;
  chain.bodies = 4;
  const Model m = make_chain(chain);
  const std::string head = R"({"model": ")" + m.name + R"(", "bodies": 4, "partitions": 2, "part_of_body": )";
  for (const auto& [parts, want] : std::vector<std::pair<std::string, std::string>>{
           {"[0, 1e300, 1, 1]", "part_of_body[1]: must be an integer"},
           {"[0, 0.5, 1, 1]", "part_of_body[1]: must be an integer"},
           {"[0, 2, 1, 1]", "part_of_body[1]: must be <= 1"},
           {"[0, -1, 1, 1]", "part_of_body[1]: must be >= 0"}}) {
    const auto p = temp_file("part.json", head + parts + "}");
    CHECK_THAT(error_of([&] { read_partition_file(m, p.string()); }), Catch::Contains(want));
    std::filesystem::remove(p);
  }
}

TEST_CASE("a random function's components are capped, and a step count must be representable", "[io][limits]") {
  ChainParams chain;
  chain.bodies = 2;
  Model m = make_chain(chain);
  Load l;
  l.body = 0;
  l.force = {1.0, 0.0, 0.0};
  l.function = TimeFunction::random(1.0, 10.0, 1, 2'000'000'000);
  m.loads.push_back(l);
  const std::string text = model_to_json(m);
  CHECK_THAT(error_of([&] { read_model_text(text, "m.json"); }), Catch::Contains("components: must be <= 65536 (got 2e+09)"));
  // An embedding program that sets it gets the same answer from the library.
  CHECK_THAT(error_of([&] { MultibodySystem sys(m); }), Catch::Contains("components must be 1 to 65536"));
  // --step 1e-300 had ended "done" after -9223372036854775808 steps.
  CHECK_THAT(error_of([] { step_grid(0.0, 1.0, 1e-300); }), Catch::Contains("more than a run can take"));
  CHECK_THAT(error_of([] { step_grid(0.0, 1.0, 0.0); }), Catch::Contains("more than a run can take"));
  CHECK(step_grid(0.0, 1.0, 0.25).steps == 4);
}

TEST_CASE("input files larger than their cap are refused unread", "[io][limits]") {
  const auto p = temp_file("huge.json", "");
  std::filesystem::resize_file(p, max_model_bytes + 1);  // sparse: nothing is written
  CHECK_THAT(error_of([&] { read_model_file(p.string()); }), Catch::Contains("more than the 1073741824 a model file may have"));
  std::filesystem::resize_file(p, (std::size_t{16} << 20) + 1);
  CHECK_THAT(error_of([&] { read_cluster_file(p.string()); }), Catch::Contains("a cluster file may have"));
  std::filesystem::remove(p);
}
