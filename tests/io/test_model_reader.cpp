#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/run_settings.hpp"

using namespace mbsflow;

namespace {
const std::string examples = MBSFLOW_EXAMPLES;
}

TEST_CASE("the features example reads with every field in place", "[io]") {
  const Model m = read_model_file(examples + "/features.json");
  REQUIRE(m.bodies.size() == 3);
  CHECK(m.bodies[1].inertia[4] == 0.001);
  CHECK(m.bodies[1].angular_velocity[1] == 0.5);
  REQUIRE(m.joints.size() == 3);
  CHECK(m.joints[0].body1 == ground);
  CHECK(m.joints[0].preload[1] == Approx(98.1));
  // Natural-frequency form: reduced mass 10*2/12 times 60^2.
  CHECK(m.joints[1].stiffness[0] == Approx(10.0 * 2.0 / 12.0 * 3600.0));
  CHECK(m.joints[1].tables[1].force.size() == 3);
  // Frame on body2 from the initial rotation of the arm (30 degrees about z).
  CHECK(m.joints[1].frame2[3] == Approx(-std::sin(M_PI / 12)));
  CHECK(m.joints[2].type == JointType::spring);
  CHECK(m.joints[2].rest_length == Approx(std::hypot(1.2 - 0.6 - 0.4 * std::cos(M_PI / 6), 0.1 - 0.4 * std::sin(M_PI / 6))));
  REQUIRE(m.loads.size() == 3);
  CHECK(m.loads[0].function.kind == TimeFunction::Kind::harmonic);
  CHECK(m.loads[1].body_frame);
  CHECK(m.loads[2].function.times.size() == 3);
  REQUIRE(m.drivers.size() == 1);
  CHECK(m.drivers[0].displacement[1].kind == TimeFunction::Kind::random);
  CHECK(m.simulation.step.value() == 2e-4);
  CHECK(m.simulation.output_every == 50);
}

TEST_CASE("models written and read back are the same model", "[io]") {
  TrainParams tp;
  tp.wagons = 2;
  GridParams gp;
  gp.rows = 3;
  gp.cols = 4;
  Model with_interval = make_chain(ChainParams{});
  with_interval.simulation.output_interval = 0.0025;
  with_interval.simulation.method = Method::tirk;
  with_interval.simulation.variant = "radau5,newton-triangular";
  Model compliant = read_model_file(examples + "/slider_crank.json");  // kinematic joints, motor, limits
  compliant.joints[1].rigid = false;
  set_bushing_from_frequency(compliant, compliant.joints[1], 300.0, 0.1);
  for (const Model& m : {read_model_file(examples + "/features.json"), with_interval, make_grid(gp), make_train(tp),
                         read_model_file(examples + "/slider_crank.json"), compliant,
                         read_model_file(examples + "/iftomm_a01_pendulum.json"),
                         read_model_file(examples + "/lead_screw.json")}) {
    const std::string once = model_to_json(m);
    const Model back = read_model_text(once, m.name);
    CHECK(model_to_json(back) == once);
    CHECK(back.simulation.output_interval == m.simulation.output_interval);
    CHECK(back.simulation.variant == m.simulation.variant);
    CHECK(back.bodies.size() == m.bodies.size());
    CHECK(back.joints.size() == m.joints.size());
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
      CHECK(back.joints[j].type == m.joints[j].type);
      CHECK(back.joints[j].rigid == m.joints[j].rigid);
      CHECK(back.joints[j].frame1 == m.joints[j].frame1);
      CHECK(back.joints[j].frame2 == m.joints[j].frame2);
      CHECK(back.joints[j].rest_length == m.joints[j].rest_length);
      CHECK(back.joints[j].motor->kind == m.joints[j].motor->kind);
      CHECK(back.joints[j].limits->upper == m.joints[j].limits->upper);
      CHECK(back.joints[j].stiffness == m.joints[j].stiffness);
      CHECK(back.joints[j].damping == m.joints[j].damping);
      CHECK(back.joints[j].frame2 == m.joints[j].frame2);
    }
  }
}

// write_model_file hands the text to the file a megabyte at a time; the file must hold
// exactly model_to_json's text, cut wherever the megabytes fall (this train's text is
// over 5 MB, with drivers after the joints).
TEST_CASE("a model file written in pieces holds exactly the model's text", "[io]") {
  TrainParams tp;
  tp.wagons = 3000;
  const Model m = make_train(tp);
  const std::filesystem::path file = std::filesystem::temp_directory_path() / ("mbsflow_writer_" + std::to_string(::getpid()) + ".json");
  write_model_file(m, file.string());
  std::ifstream in(file, std::ios::binary);
  const std::string written((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string text = model_to_json(m);
  CHECK(text.size() > (std::size_t{5} << 20));
  CHECK(written == text);
  std::filesystem::remove(file);
}

TEST_CASE("input errors carry file, line, column and field path", "[io]") {
  const std::string text = "{\n  \"bodies\": [\n    {\"name\": \"a\", \"mass\": -1, \"inertia\": [1, 1, 1]}\n  ]\n}\n";
  try {
    read_model_text(text, "m.json");
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()) == "m.json:3:27: bodies[0].mass: must be > 0 (got -1)");
  }
}

TEST_CASE("a model reads the same whatever the order of its top-level fields", "[io]") {
  // Bodies are read as the text streams by; joints, loads and drivers listed before them wait.
  const std::string text = model_to_json(read_model_file(examples + "/features.json"));
  const auto j = nlohmann::ordered_json::parse(text);
  nlohmann::ordered_json reversed = nlohmann::ordered_json::object();
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  REQUIRE(keys.front() == "name");
  for (auto k = keys.rbegin(); k != keys.rend(); ++k) reversed[*k] = j[*k];
  const std::string reversed_text = reversed.dump(2);
  REQUIRE(reversed_text.find("\"joints\"") < reversed_text.find("\"bodies\""));
  const Model back = read_model_text(reversed_text, "reversed.json");
  CHECK(model_to_json(back) == text);
}

TEST_CASE("a top-level list given twice is refused", "[io]") {
  const std::string text =
      "{\"bodies\": [{\"name\": \"a\", \"mass\": 1, \"inertia\": [1, 1, 1]}],\n"
      " \"bodies\": [{\"name\": \"b\", \"mass\": 1, \"inertia\": [1, 1, 1]}]}";
  CHECK_THROWS_AS(read_model_text(text, "m.json"), InputError);
  CHECK_THROWS_WITH(read_model_text(text, "m.json"), "m.json: bodies: given twice");
}

TEST_CASE("a list that is not an array fails as a missing one does: with its path", "[io]") {
  const std::string base = "{\"bodies\": [{\"name\": \"a\", \"mass\": 1, \"inertia\": [1, 1, 1]}]";
  CHECK_THROWS_WITH(read_model_text(base + ", \"joints\": {}}", "m.json"), "m.json:1:72: joints: must be an array (got object)");
  CHECK_THROWS_WITH(read_model_text("{\"bodies\": 3}", "m.json"), "m.json:1:12: bodies: must be an array (got number)");
  CHECK_THROWS_WITH(read_model_text("{\"bodies\": []}", "m.json"), "m.json:1:12: bodies: must list at least one body");
  CHECK_THROWS_WITH(read_model_text("{}", "m.json"), "m.json:1:1: missing field 'bodies'");
}

TEST_CASE("the simulation block takes the settings declared for models, each checked as declared", "[io]") {
  const nlohmann::json block = {{"t_start", 0.5}, {"t_end", 2.0},          {"step", 1e-3},
                                {"method", "tirk"}, {"variant", "radau5"}, {"output_every", 5},
                                {"output_interval", 0.01}, {"rtol", 1e-5}, {"atol", 1e-7}, {"assemble", true}};
  std::set<std::string> declared;
  for (const RunSetting& s : run_settings())
    if (s.places & in_model) declared.insert(s.name);
  std::set<std::string> given;
  for (const auto& [key, value] : block.items()) given.insert(key);
  CHECK(given == declared);  // a setting declared for models is read here too
  auto model = [](const nlohmann::json& sim) {
    const nlohmann::json m = {{"bodies", {{{"name", "a"}, {"mass", 1.0}, {"inertia", {1.0, 1.0, 1.0}}}}}, {"simulation", sim}};
    return read_model_text(m.dump(), "m.json");
  };
  const Model m = model(block);
  CHECK(m.simulation.t_start == 0.5);
  CHECK(m.simulation.t_end == 2.0);
  CHECK(m.simulation.method == Method::tirk);
  CHECK(m.simulation.variant == "radau5");
  CHECK(m.simulation.output_every == 5);
  CHECK(m.simulation.output_interval == 0.01);
  CHECK(m.simulation.assemble);
  CHECK(read_model_text(model_to_json(m), "back").simulation.output_interval == 0.01);
  auto error = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json sim = block;
    sim[key] = value;
    try {
      model(sim);
    } catch (const InputError& e) {
      const std::string text = e.what();
      return text.substr(text.find("simulation"));
    }
    return std::string("no error");
  };
  CHECK(error("step", 0) == "simulation.step: must be > 0 (got 0)");
  CHECK(error("output_every", 0) == "simulation.output_every: must be >= 1 (got 0)");
  CHECK(error("output_every", 2.5) == "simulation.output_every: must be an integer (got 2.5)");
  CHECK(error("method", "euler") == "simulation.method: must be one of rk4, dopri5, colloc, tirk (got 'euler')");
  CHECK(error("t_end", 0.25) == "simulation.t_end: must be > t_start (0.5, got 0.25)");
  CHECK(error("assemble", 1).find("simulation.assemble:") == 0);
  CHECK(error("threads", 2).find("simulation.threads: unknown field (expected one of: t_start, t_end") == 0);
}
