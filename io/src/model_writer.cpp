#include "mbsflow/io/model_writer.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

using json = nlohmann::ordered_json;

bool zero(const Vec3& v) { return v == Vec3{}; }
bool identity(const Quat& q) { return q == Quat{1.0, 0.0, 0.0, 0.0}; }

json function_json(const TimeFunction& f) {
  json j;
  switch (f.kind) {
    case TimeFunction::Kind::constant:
      j = {{"type", "constant"}, {"value", f.value}};
      break;
    case TimeFunction::Kind::harmonic:
      j = {{"type", "harmonic"}, {"amplitude", f.amplitude}, {"frequency", f.frequency}};
      if (f.phase != 0.0) j["phase"] = f.phase;
      if (f.offset != 0.0) j["offset"] = f.offset;
      break;
    case TimeFunction::Kind::table:
      j = {{"type", "table"}, {"t", f.times}, {"value", f.values}};
      break;
    case TimeFunction::Kind::random:
      j = {{"type", "random"}, {"amplitude", f.amplitude}, {"cutoff", f.cutoff}, {"seed", f.seed},
           {"components", f.components}};
      break;
  }
  if (f.delay != 0.0) j["delay"] = f.delay;
  return j;
}

bool is_zero_constant(const TimeFunction& f) { return f.kind == TimeFunction::Kind::constant && f.value == 0.0 && f.delay == 0.0; }

json body_json(const Body& b) {
  json j = {{"name", b.name}, {"mass", b.mass}};
  const bool diagonal = b.inertia[3] == 0.0 && b.inertia[4] == 0.0 && b.inertia[5] == 0.0;
  j["inertia"] = diagonal ? json{b.inertia[0], b.inertia[1], b.inertia[2]} : json(b.inertia);
  j["position"] = b.position;
  if (!identity(b.orientation)) j["orientation"] = b.orientation;
  if (!zero(b.velocity)) j["velocity"] = b.velocity;
  if (!zero(b.angular_velocity)) j["angular_velocity"] = b.angular_velocity;
  return j;
}

void kinematic_fields(const Joint& jt, json& j) {
  j["frame2"] = jt.frame2;
  if (jt.type == JointType::distance) j["length"] = jt.rest_length;
  if (!jt.rigid) {
    j["rigid"] = false;
    j["stiffness"] = jt.stiffness;
    j["damping"] = jt.damping;
  }
  if (jt.motor.kind != JointMotor::Kind::none) {
    const char* kind = jt.motor.kind == JointMotor::Kind::position ? "position"
                       : jt.motor.kind == JointMotor::Kind::velocity ? "velocity" : "effort";
    j["motor"] = {{"type", kind}, {"function", function_json(jt.motor.function)}};
  }
  if (jt.limits.active)
    j["limits"] = {{"lower", jt.limits.lower}, {"upper", jt.limits.upper}, {"stiffness", jt.limits.stiffness},
                   {"damping", jt.limits.damping}};
}

json joint_json(const Model& m, const Joint& jt) {
  auto name = [&](int b) { return b == ground ? std::string("ground") : m.bodies[static_cast<std::size_t>(b)].name; };
  json j = {{"name", jt.name}, {"type", joint_type_name(jt.type)},
            {"body1", name(jt.body1)}, {"body2", name(jt.body2)}, {"point1", jt.point1}, {"point2", jt.point2}};
  if (is_kinematic(jt.type)) {
    if (!identity(jt.frame1)) j["frame1"] = jt.frame1;
    kinematic_fields(jt, j);
    return j;
  }
  if (jt.type == JointType::spring) {
    j["stiffness"] = jt.stiffness[0];
    if (jt.damping[0] != 0.0) j["damping"] = jt.damping[0];
    j["rest_length"] = jt.rest_length;
    return j;
  }
  if (!identity(jt.frame1)) j["frame1"] = jt.frame1;
  if (jt.frame2 != rest_frame2(m, jt)) j["frame2"] = jt.frame2;
  j["stiffness"] = jt.stiffness;
  if (jt.damping != Vec6{}) j["damping"] = jt.damping;
  static const char* axes[6] = {"x", "y", "z", "rx", "ry", "rz"};
  json tables = json::object();
  for (std::size_t a = 0; a < 6; ++a)
    if (!jt.tables[a].empty()) tables[axes[a]] = {{"deflection", jt.tables[a].deflection}, {"force", jt.tables[a].force}};
  if (!tables.empty()) j["tables"] = tables;
  if (jt.preload != Vec6{}) j["preload"] = jt.preload;
  return j;
}

}  // namespace

// One body or joint per line: readable, and error line numbers stay meaningful. Each item
// is made and written in turn, so that no document of the whole model is ever held: a
// million-body model's document tree would take gigabytes.
std::string model_to_json(const Model& m) {
  std::string out = "{\n";
  auto key = [&out](const char* k) { out += (out.size() > 2 ? ",\n  " : "  ") + json(k).dump() + ": "; };
  auto list = [&](const char* k, std::size_t n, const auto& item) {
    key(k);
    if (n == 0) {
      out += "[]";
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < n; ++i) out += "    " + item(i).dump() + (i + 1 < n ? ",\n" : "\n");
    out += "  ]";
  };
  key("name");
  out += json(m.name).dump();
  key("gravity");
  out += json(m.gravity).dump();
  list("bodies", m.bodies.size(), [&](std::size_t i) { return body_json(m.bodies[i]); });
  list("joints", m.joints.size(), [&](std::size_t i) { return joint_json(m, m.joints[i]); });
  if (!m.loads.empty()) {
    list("loads", m.loads.size(), [&](std::size_t i) {
      const Load& l = m.loads[i];
      json j = {{"body", m.bodies[static_cast<std::size_t>(l.body)].name}, {"force", l.force}, {"torque", l.torque}};
      if (!zero(l.point)) j["point"] = l.point;
      if (l.body_frame) j["frame"] = "body";
      j["function"] = function_json(l.function);
      return j;
    });
  }
  if (!m.drivers.empty()) {
    list("drivers", m.drivers.size(), [&](std::size_t i) {
      const Driver& d = m.drivers[i];
      json motion = json::object();
      if (!zero(d.velocity)) motion["velocity"] = d.velocity;
      static const char* axes[3] = {"x", "y", "z"};
      for (std::size_t a = 0; a < 3; ++a)
        if (!is_zero_constant(d.displacement[a])) motion[axes[a]] = function_json(d.displacement[a]);
      return json{{"body", m.bodies[static_cast<std::size_t>(d.body)].name}, {"motion", motion}};
    });
  }
  const SimulationSettings& s = m.simulation;
  json sim = {{"t_start", s.t_start}, {"t_end", s.t_end}, {"method", method_name(s.method)},
              {"output_every", s.output_every}, {"rtol", s.rtol}, {"atol", s.atol}};
  if (s.step) sim["step"] = *s.step;
  if (!s.variant.empty()) sim["variant"] = s.variant;
  if (s.output_interval) sim["output_interval"] = *s.output_interval;
  key("simulation");
  out += sim.dump();
  return out + "\n}\n";
}

void write_model_file(const Model& model, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path + ": cannot write the model file");
  out << model_to_json(model);
  if (!out) throw InputError(path + ": error while writing the model file");
}

}  // namespace mbsflow
