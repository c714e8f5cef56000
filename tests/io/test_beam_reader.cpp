// The "beams" of a model file: node bodies and element bushings named after the beam,
// referred to by joints and loads wherever the lists stand, and bad data refused with the
// field named.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "mbsflow/error.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"

using namespace mbsflow;

namespace {

const std::string beam = R"({"name": "blade", "from": [0, 0, 0], "to": [2, 0, 0], "up": [0, 1, 0], "elements": 4,
  "E": 2.1e11, "G": 8.1e10, "density": 7850, "section": {"area": 1e-4, "Iy": 8.33e-10, "Iz": 8.33e-10, "J": 1.41e-9}})";

std::string model(const std::string& beams, bool joints_first) {
  const std::string joints = R"("joints": [{"name": "root", "type": "fixed", "body1": "hub", "body2": "blade.0"}],
    "loads": [{"body": "blade.4", "force": [0, -1, 0]}])";
  const std::string b = "\"beams\": [" + beams + "]";
  return R"({"name": "m", "bodies": [{"name": "hub", "mass": 1, "inertia": [1, 1, 1]}], )" +
         (joints_first ? joints + ", " + b : b + ", " + joints) + "}";
}

std::string with(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

}  // namespace

TEST_CASE("a beam becomes node bodies and element bushings that joints and loads name, whatever the order", "[io][beams]") {
  for (bool joints_first : {true, false}) {
    INFO("joints " << (joints_first ? "before" : "after") << " the beams");
    const Model m = read_model_text(model(beam, joints_first), "m.json");
    REQUIRE(m.bodies.size() == 6);
    CHECK(m.bodies[1].name == "blade.0");
    CHECK(m.bodies[5].name == "blade.4");
    CHECK(m.bodies[5].position[0] == 2.0);
    double mass = 0;
    for (std::size_t i = 1; i < 6; ++i) mass += m.bodies[i].mass;
    CHECK(mass == Approx(7850 * 1e-4 * 2.0).epsilon(1e-14));
    CHECK(m.bodies[1].mass == Approx(0.5 * m.bodies[2].mass));  // half an element at each end
    REQUIRE(m.beams.size() == 1);
    CHECK(m.beams[0].name == "blade");
    CHECK(m.beams[0].first_body == 1);
    CHECK(m.beams[0].nodes == 5);
    CHECK(m.beams[0].elements == 4);
    const Joint& e0 = m.joints[static_cast<std::size_t>(m.beams[0].first_joint)];
    CHECK(e0.name == "blade.e0");
    CHECK(e0.type == JointType::bushing);
    const Vec6& k = e0.stiffness;
    const double l = 0.5;
    CHECK(k[0] == Approx(2.1e11 * 1e-4 / l));                      // axial EA/L
    CHECK(k[1] == Approx(12 * 2.1e11 * 8.33e-10 / (l * l * l)));   // shear 12 E I/L^3
    CHECK(k[3] == Approx(8.1e10 * 1.41e-9 / l));                   // torsion G J/L
    CHECK(k[5] == Approx(2.1e11 * 8.33e-10 / l));                  // bending E I/L
    const auto root = std::find_if(m.joints.begin(), m.joints.end(), [](const Joint& j) { return j.name == "root"; });
    REQUIRE(root != m.joints.end());
    CHECK(root->body2 == 1);
    REQUIRE(m.loads.size() == 1);
    CHECK(m.loads[0].body == 5);
  }
}

TEST_CASE("a beam model written and read back is the same model, its beam as bodies and bushings", "[io][beams]") {
  const Model m = read_model_text(model(beam, false), "m.json");
  const Model back = read_model_text(model_to_json(m), "back.json");
  REQUIRE(back.bodies.size() == m.bodies.size());
  REQUIRE(back.joints.size() == m.joints.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) CHECK(back.bodies[i].name == m.bodies[i].name);
  const Joint &a = m.joints[0], &b = back.joints[0];
  for (std::size_t i = 0; i < 6; ++i) CHECK(static_cast<const Vec6&>(b.stiffness)[i] == static_cast<const Vec6&>(a.stiffness)[i]);
  for (std::size_t i = 0; i < 4; ++i) CHECK(static_cast<const Quat&>(b.frame2)[i] == Approx(static_cast<const Quat&>(a.frame2)[i]));
}

TEST_CASE("bad beam data is refused with the field named", "[io][beams]") {
  const auto refused = [](const std::string& b, const std::string& expected) {
    INFO(b);
    CHECK_THROWS_WITH(read_model_text(model(b, false), "m.json"), Catch::Contains(expected));
  };
  refused(with(beam, "\"area\": 1e-4", "\"area\": 0"), "beams[0].section.area: must be > 0");
  refused(with(beam, "\"E\": 2.1e11", "\"E\": -1"), "beams[0].E: must be > 0");
  refused(with(beam, "\"elements\": 4", "\"elements\": 0"), "beams[0].elements");
  refused(with(beam, "\"up\": [0, 1, 0]", "\"up\": [1, 0, 0]"), "beams[0].up: beam 'blade': up is parallel to the beam's axis");
  refused(with(beam, "\"to\": [2, 0, 0]", "\"to\": [0, 0, 0]"), "coincide");
  refused(with(beam, "\"name\": \"blade\"", "\"name\": \"hub\", \"extra\": 1"), "beams[0].extra: unknown field");
  refused(with(beam, "\"name\": \"blade\"", "\"name\": \"a.b\""), "must not hold '.'");
  // Its nodes' names are bodies' names like any other.
  refused(with(beam, "\"name\": \"blade\"", "\"name\": \"hub\"") + ", " + with(beam, "\"name\": \"blade\"", "\"name\": \"hub\""),
          "duplicate body name 'hub.0'");
}

TEST_CASE("a beam's Rayleigh damping: beta on its elements, alpha as damping loads on its nodes that write and read back",
          "[io][beams]") {
  const std::string damped = with(beam, "\"elements\": 4", "\"elements\": 4, \"damping\": {\"alpha\": 2.5, \"beta\": 1e-4}");
  const Model m = read_model_text(model(damped, false), "m.json");
  REQUIRE(m.loads.size() == 1 + 5);  // the tip load and one per node
  CHECK(static_cast<const Vec6&>(m.joints[0].damping)[0] == Approx(1e-4 * static_cast<const Vec6&>(m.joints[0].stiffness)[0]));
  const auto at = std::find_if(m.loads.begin(), m.loads.end(), [](const Load& l) { return l.body == 2 && l.damped(); });
  REQUIRE(at != m.loads.end());  // blade.1's
  const Load& node = *at;
  const std::size_t k = static_cast<std::size_t>(at - m.loads.begin());
  CHECK(node.damping[1] == Approx(2.5 * m.bodies[2].mass));
  CHECK(node.angular_damping[0] == Approx(2.5 * m.bodies[2].inertia.get()[0]));
  CHECK(node.force == Vec3{});
  const Model back = read_model_text(model_to_json(m), "back.json");
  REQUIRE(back.loads.size() == m.loads.size());
  CHECK(back.loads[k].damping == node.damping);
  CHECK(back.loads[k].angular_damping == node.angular_damping);
  // alpha alone is a beam with no stiffness-proportional part
  const Model alpha_only = read_model_text(model(with(beam, "\"elements\": 4", "\"elements\": 4, \"damping\": {\"alpha\": 1}"), false), "a.json");
  CHECK(static_cast<const Vec6&>(alpha_only.joints[0].damping)[0] == 0.0);
  CHECK(alpha_only.loads.size() == 6);
  CHECK_THROWS_WITH(read_model_text(model(with(beam, "\"elements\": 4", "\"elements\": 4, \"damping\": {\"alpha\": -1}"), false), "a.json"),
                    Catch::Contains("alpha: must be >= 0"));
  CHECK_THROWS_WITH(read_model_text(R"({"name": "m", "bodies": [{"name": "a", "mass": 1, "inertia": [1, 1, 1]}], "loads": [{"body": "a", "damping": [1, -1, 0]}]})", "l.json"),
                    Catch::Contains("loads[0].damping[1]"));
}
