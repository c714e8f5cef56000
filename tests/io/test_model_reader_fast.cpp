// The fast model reader (json_tape.hpp, model_reading.hpp) against the reference reader
// (nlohmann-json): the same model wherever it reads, and it gives up (leaving the
// reference to read and to report) on everything outside its subset and on every error.
#include <catch2/catch.hpp>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "json_node.hpp"
#include "json_tape.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "model_reading.hpp"

using namespace mbsflow;

namespace {

const std::string examples = MBSFLOW_EXAMPLES;

std::string reference_error(const std::string& text) {
  try {
    read_model_reference(text, "m.json");
  } catch (const InputError& e) {
    return e.text();
  }
  return "";
}

// Both readers give the same model: its text written back, and its numbers bit for bit.
void check_same_model(const std::string& text, bool fast_expected) {
  const Model reference = read_model_reference(text, "m.json");
  const std::optional<Model> fast = read_model_fast(text, "m.json");
  REQUIRE(fast.has_value() == fast_expected);
  const Model read = read_model_text(text, "m.json");
  CHECK(model_to_json(read) == model_to_json(reference));
  if (!fast) return;
  CHECK(model_to_json(*fast) == model_to_json(reference));
  REQUIRE(fast->bodies.size() == reference.bodies.size());
  for (std::size_t i = 0; i < reference.bodies.size(); ++i) {
    CHECK(fast->bodies[i].name == reference.bodies[i].name);
    CHECK(fast->bodies[i].position == reference.bodies[i].position);
    CHECK(fast->bodies[i].inertia == reference.bodies[i].inertia);
  }
  REQUIRE(fast->joints.size() == reference.joints.size());
  for (std::size_t i = 0; i < reference.joints.size(); ++i) {
    CHECK(fast->joints[i].stiffness == reference.joints[i].stiffness);
    CHECK(fast->joints[i].damping == reference.joints[i].damping);
    CHECK(fast->joints[i].frame2 == reference.joints[i].frame2);
  }
}

const char* two_bodies = R"({"name": "two", "gravity": [0, -9.81, 0],
  "bodies": [{"name": "a", "mass": 1, "inertia": [1, 1, 1]}, {"name": "b", "mass": 2, "inertia": [1, 1, 1], "position": [1, 0, 0]}],
  "joints": [{"type": "bushing", "body1": "a", "body2": "b", "stiffness": [1, 1, 1, 1, 1, 1]}]})";

std::string replaced(std::string text, const std::string& what, const std::string& by) {
  const auto at = text.find(what);
  REQUIRE(at != std::string::npos);
  return text.replace(at, what.size(), by);
}

}  // namespace

TEST_CASE("the fast reader reads the examples and generated models as the reference does", "[io]") {
  for (const auto& e : std::filesystem::directory_iterator(examples)) {
    if (e.path().extension() != ".json") continue;
    INFO(e.path().string());
    const std::string text = read_model_file_text(e.path().string());
    check_same_model(text, text.find("\"beams\"") == std::string::npos);  // beams: the reference reader's
  }
  GridParams gp;
  gp.rows = 5;
  gp.cols = 7;
  TrainParams tp;
  tp.wagons = 3;
  ChainParams cp;
  cp.bodies = 300;
  for (const Model& m : {make_chain(cp), make_grid(gp), make_train(tp)}) {
    INFO(m.name);
    check_same_model(model_to_json(m), true);
  }
}

TEST_CASE("the fast reader converts numbers bit for bit as nlohmann does", "[io]") {
  // Integers past 2^53 and past 64 bits, -0 as an integer (nlohmann: +0) and as a float,
  // exponents, the shortest and longest spellings of doubles.
  for (const char* x : {"9007199254740993", "18446744073709551617", "123456789012345678901234567890", "-0", "-0.0", "1E2",
                        "2.5e-3", "0.1", "4.9406564584124654e-324", "1.7976931348623157e308", "0.30000000000000004"}) {
    INFO(x);
    const std::string text = replaced(two_bodies, "\"position\": [1, 0, 0]", std::string("\"position\": [") + x + ", 0, 0]");
    check_same_model(text, true);
    const Model fast = *read_model_fast(text, "m.json");
    const Model reference = read_model_reference(text, "m.json");
    CHECK(std::signbit(fast.bodies[1].position[0]) == std::signbit(reference.bodies[1].position[0]));
  }
  // Whitespace of every kind, lists in any order (joints before bodies).
  check_same_model(replaced(replaced(two_bodies, "\"mass\": 1,", "\t\"mass\"\r\n:\n1 ,"), "[1, 1, 1]}", "[ 1 ,1,1 ] }"), true);
  const std::string joints_first = R"({"joints": [{"type": "spring", "body1": "a", "body2": "b", "stiffness": 3}],
    "bodies": [{"name": "a", "mass": 1, "inertia": [1, 1, 1]}, {"name": "b", "mass": 2, "inertia": [1, 1, 1], "position": [1, 0, 0]}]})";
  check_same_model(joints_first, true);
}

TEST_CASE("text outside the fast reader's subset is read by the reference reader, the same model", "[io]") {
  // Escapes and non-ASCII in a name; a key given twice in an item (nlohmann keeps the
  // last); a description in UTF-8 (only items must be plain: the rest goes to nlohmann).
  check_same_model(replaced(two_bodies, "{\"type\": \"bushing\"", "{\"name\": \"\\u00e4\", \"type\": \"bushing\""), false);
  check_same_model(replaced(two_bodies, "{\"type\": \"bushing\"", "{\"name\": \"\xc3\xa4\", \"type\": \"bushing\""), false);
  check_same_model(replaced(two_bodies, "\"mass\": 2,", "\"mass\": 5, \"mass\": 2,"), false);
  check_same_model(replaced(two_bodies, "\"name\": \"two\",", "\"name\": \"two\", \"description\": \"Kr\xc3\xa4" "fte \\\"quoted\\\"\","),
                   true);
}

TEST_CASE("the fast reader gives up on every bad model and the reference reports it", "[io]") {
  const std::string dir = std::string(MBSFLOW_EXAMPLES) + "/../../tests/io/bad_models";
  int models = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() != ".json") continue;
    INFO(e.path().string());
    const std::string text = read_model_file_text(e.path().string());
    const std::string error = reference_error(text);
    if (error.empty()) {  // a model that reads and fails later (a run's checks)
      check_same_model(text, true);
      continue;
    }
    CHECK_FALSE(read_model_fast(text, "m.json").has_value());
    try {
      read_model_text(text, "m.json");
      FAIL("read without an error");
    } catch (const InputError& x) {
      CHECK(x.text() == error);
    }
    ++models;
  }
  CHECK(models >= 20);
  // Errors within the fast reader's subset, the reference's message each time: a trailing
  // comma, text after the document, a number past the double range, a bad item.
  for (const std::string& bad : {replaced(two_bodies, "[1, 0, 0]}", "[1, 0, 0],}"), std::string(two_bodies) + " x",
                                 replaced(two_bodies, "\"mass\": 2", "\"mass\": 1e999"),
                                 replaced(two_bodies, "\"mass\": 2", "\"mass\": -2"),
                                 replaced(two_bodies, "\"mass\": 2", "\"mas\": 2"), replaced(two_bodies, "[1, 0, 0]", "[1, 0]")}) {
    INFO(bad);
    CHECK_FALSE(read_model_fast(bad, "m.json").has_value());
    const std::string error = reference_error(bad);
    REQUIRE_FALSE(error.empty());
    CHECK_THROWS_WITH(read_model_text(bad, "m.json"), Catch::Contains(error));
  }
}

TEST_CASE("a tape holds a value's entries in document order with their extents", "[io]") {
  JsonTape tape;
  const std::string text = R"({"a": [1, {"b": null}, true], "c": "x"} tail)";
  const std::size_t end = parse_json_tape(text, 0, 8, tape);
  CHECK(text.substr(end) == " tail");
  // object, "a", array, 1, object, "b", null, true, "c", "x"
  REQUIRE(tape.entries.size() == 10);
  CHECK(tape.entries[0].kind == JsonTape::Kind::object);
  CHECK(tape.entries[0].count == 2);
  CHECK(tape.entries[0].end == 10);
  CHECK(tape.entries[1].text == "a");
  CHECK(tape.entries[2].kind == JsonTape::Kind::array);
  CHECK(tape.entries[2].count == 3);
  CHECK(tape.entries[2].end == 8);
  CHECK(tape.entries[4].end == 7);
  CHECK(tape.entries[6].kind == JsonTape::Kind::null);
  CHECK(tape.entries[7].kind == JsonTape::Kind::boolean);
  CHECK(tape.entries[7].flag);
  CHECK(tape.entries[9].text == "x");
  // Nesting past the limit, escapes, bad literals: it gives up.
  CHECK(parse_json_tape("[[[1]]]", 0, 2, tape) == std::string_view::npos);
  CHECK(parse_json_tape("[[[1]]]", 0, 3, tape) == 7);
  CHECK(parse_json_tape(R"("a\"b")", 0, 3, tape) == std::string_view::npos);
  CHECK(parse_json_tape("[tru]", 0, 3, tape) == std::string_view::npos);
  CHECK(parse_json_tape("[01]", 0, 3, tape) == std::string_view::npos);
  CHECK(parse_json_tape("[1.]", 0, 3, tape) == std::string_view::npos);
  CHECK(parse_json_tape("[NaN]", 0, 3, tape) == std::string_view::npos);
}

TEST_CASE("the fast reader reads lists of many batches in order and stops at an error in a late one", "[io]") {
  // 30 x 30 bodies and 1740 joints: lists of several batches, parsed on one thread while
  // another reads the items (json_tape_list.hpp).
  GridParams gp;
  gp.rows = 30;
  gp.cols = 30;
  const Model grid = make_grid(gp);
  const std::string text = model_to_json(grid);
  check_same_model(text, true);
  SECTION("joints get room for as many items as the rest of the text can hold, not twice the bodies' count") {
    // A chain with a third more joints than bodies: room for the bodies' count, then
    // doubling, would leave room for 1.5 times them.
    ChainParams cp;
    cp.bodies = 900;
    Model chain = make_chain(cp);
    for (int i = 0; i + 2 < cp.bodies; i += 3) {
      Joint j;
      j.name = "spring" + std::to_string(i);
      j.type = JointType::spring;
      j.body1 = i;
      j.body2 = i + 2;
      j.stiffness.set(0, 1.0);
      chain.joints.push_back(j);
    }
    const Model m = *read_model_fast(model_to_json(chain), "m.json");
    REQUIRE(m.joints.size() == chain.joints.size());
    CHECK(m.joints.capacity() < m.joints.size() + m.joints.size() / 5);
  }
  SECTION("the joints listed before the bodies, read once the bodies are") {
    const auto comma = text.find(",\n  \"joints\"");  // model_writer's layout
    REQUIRE(comma != std::string::npos);
    REQUIRE(text.find("\"bodies\"") < comma);
    const auto after = text.find("\n  ]", comma) + 4;  // after the joints list's ']'
    const std::string list = text.substr(comma + 4, after - comma - 4);
    std::string moved = text;
    moved.erase(comma, after - comma);
    moved.insert(moved.find('{') + 1, "\n  " + list + ",");
    check_same_model(moved, true);
  }
  SECTION("an error or text outside the subset in the last batch") {
    const std::string last_body = grid.bodies.back().name, last_joint = grid.joints.back().name;
    const std::string unknown_body = replaced(text, "\"body2\":\"" + last_body + "\"", "\"body2\":\"nobody\"");
    CHECK_FALSE(read_model_fast(unknown_body, "m.json").has_value());
    const std::string error = reference_error(unknown_body);
    REQUIRE_THAT(error, Catch::Contains("unknown body 'nobody'"));
    CHECK_THROWS_WITH(read_model_text(unknown_body, "m.json"), Catch::Contains(error));
    check_same_model(replaced(text, "\"name\":\"" + last_joint + "\"", "\"name\":\"\\u00e4\""), false);
  }
}

TEST_CASE("both readers store a value that the joints or bodies of a file repeat once", "[io]") {
  ChainParams cp;
  cp.bodies = 50;
  const std::string text = model_to_json(make_chain(cp));
  for (bool fast : {true, false}) {
    INFO((fast ? "fast" : "reference"));
    const Model m = fast ? *read_model_fast(text, "m.json") : read_model_reference(text, "m.json");
    REQUIRE(m.joints.size() == 50);
    for (std::size_t k = 2; k < m.joints.size(); ++k) {
      CHECK(&m.joints[k].stiffness.get() == &m.joints[1].stiffness.get());
      CHECK(&m.joints[k].damping.get() == &m.joints[1].damping.get());
      CHECK(&m.joints[k].point1.get() == &m.joints[1].point1.get());
      CHECK(&m.joints[k].point2.get() == &m.joints[1].point2.get());
    }
    CHECK(m.joints[1].stiffness == make_chain(cp).joints[1].stiffness);
    for (const Body& b : m.bodies) CHECK(&b.inertia.get() == &m.bodies[0].inertia.get());
  }
}
