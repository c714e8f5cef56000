#include <catch2/catch.hpp>
#include <cmath>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"

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
                         read_model_file(examples + "/iftomm_a01_pendulum.json")}) {
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
      CHECK(back.joints[j].motor.kind == m.joints[j].motor.kind);
      CHECK(back.joints[j].limits.upper == m.joints[j].limits.upper);
      CHECK(back.joints[j].stiffness == m.joints[j].stiffness);
      CHECK(back.joints[j].damping == m.joints[j].damping);
      CHECK(back.joints[j].frame2 == m.joints[j].frame2);
    }
  }
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
