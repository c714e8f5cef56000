#include "mbsflow/io/model_writer.hpp"

#include <array>
#include <fstream>
#include <string_view>

#include "json_text.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

using json_text::Object;

bool zero(const Vec3& v) { return v == Vec3{}; }
bool identity(const Quat& q) { return q == Quat{1.0, 0.0, 0.0, 0.0}; }

void function_fields(const TimeFunction& f, Object& o) {
  switch (f.kind) {
    case TimeFunction::Kind::constant:
      o("type", "constant")("value", f.value);
      break;
    case TimeFunction::Kind::harmonic:
      o("type", "harmonic")("amplitude", f.amplitude)("frequency", f.frequency);
      if (f.phase != 0.0) o("phase", f.phase);
      if (f.offset != 0.0) o("offset", f.offset);
      break;
    case TimeFunction::Kind::table:
      o("type", "table")("t", f.times)("value", f.values);
      break;
    case TimeFunction::Kind::random:
      o("type", "random")("amplitude", f.amplitude)("cutoff", f.cutoff)("seed", f.seed)("components", f.components);
      break;
  }
  if (f.delay != 0.0) o("delay", f.delay);
}

auto function_of(const TimeFunction& f) {
  return [&f](Object& o) { function_fields(f, o); };
}

bool is_zero_constant(const TimeFunction& f) { return f.kind == TimeFunction::Kind::constant && f.value == 0.0 && f.delay == 0.0; }

// The text of the values that records share (a Defaulted field's node, or its default:
// every bushing of a generated grid holds the same points, stiffness and damping),
// written once per value: while the model is written, one address holds one value. Most
// of the writer's time went to formatting numbers, two thirds of them such repeats.
class SharedText {
 public:
  template <class T, class Write>
  std::string_view operator()(int field, const T& value, Write&& write) {
    const void* at = &value;
    for (const Slot& s : slots_)
      if (s.at == at && s.field == field) return s.text;
    Slot& s = slots_[next_];
    next_ = (next_ + 1) % slots_.size();
    s.at = at;
    s.field = field;
    s.text.clear();
    write(s.text, value);
    return s.text;
  }
  template <class T>
  std::string_view operator()(int field, const T& value) {
    return (*this)(field, value, [](std::string& out, const T& v) { json_text::write(out, v); });
  }

 private:
  struct Slot {
    const void* at = nullptr;
    int field = -1;
    std::string text;
  };
  std::array<Slot, 16> slots_;
  std::size_t next_ = 0;
};

enum SharedField { inertia_text, point1_text, point2_text, stiffness_text, damping_text, preload_text };

void write_body(std::string& out, const Body& b, SharedText& shared) {
  Object o(out);
  o("name", b.name)("mass", b.mass);
  o.raw("inertia", shared(inertia_text, b.inertia.get(), [](std::string& text, const Vec6& i) {
    if (i[3] == 0.0 && i[4] == 0.0 && i[5] == 0.0)
      json_text::write(text, std::array<double, 3>{i[0], i[1], i[2]});
    else
      json_text::write(text, i);
  }));
  o("position", b.position);
  if (!identity(b.orientation)) o("orientation", b.orientation);
  if (!zero(b.velocity)) o("velocity", b.velocity);
  if (!zero(b.angular_velocity)) o("angular_velocity", b.angular_velocity);
}

void kinematic_fields(const Joint& jt, Object& o) {
  o("frame2", jt.frame2.get());
  if (jt.type == JointType::distance) o("length", jt.rest_length);
  if (jt.type == JointType::screw) o("pitch", jt.rest_length);
  if (!jt.rigid) o("rigid", false)("stiffness", jt.stiffness.get())("damping", jt.damping.get());
  if (jt.motor->kind != JointMotor::Kind::none) {
    const char* kind = jt.motor->kind == JointMotor::Kind::position ? "position"
                       : jt.motor->kind == JointMotor::Kind::velocity ? "velocity" : "effort";
    o.object("motor", [&](Object& motor) { motor("type", kind).object("function", function_of(jt.motor->function)); });
  }
  if (jt.limits->active)
    o.object("limits", [&](Object& l) {
      l("lower", jt.limits->lower)("upper", jt.limits->upper)("stiffness", jt.limits->stiffness)("damping", jt.limits->damping);
    });
}

void write_joint(std::string& out, const Model& m, const Joint& jt, SharedText& shared) {
  auto name = [&](int b) -> const std::string& {
    static const std::string ground_name = "ground";
    return b == ground ? ground_name : m.bodies[static_cast<std::size_t>(b)].name;
  };
  Object o(out);
  o("name", jt.name)("type", joint_type_name(jt.type))("body1", name(jt.body1))("body2", name(jt.body2));
  o.raw("point1", shared(point1_text, jt.point1.get())).raw("point2", shared(point2_text, jt.point2.get()));
  if (is_kinematic(jt.type)) {
    if (!identity(jt.frame1)) o("frame1", jt.frame1.get());
    kinematic_fields(jt, o);
    return;
  }
  if (jt.type == JointType::spring) {
    o("stiffness", jt.stiffness[0]);
    if (jt.damping[0] != 0.0) o("damping", jt.damping[0]);
    o("rest_length", jt.rest_length);
    return;
  }
  if (!identity(jt.frame1)) o("frame1", jt.frame1.get());
  if (jt.frame2 != rest_frame2(m, jt)) o("frame2", jt.frame2.get());
  o.raw("stiffness", shared(stiffness_text, jt.stiffness.get()));
  if (jt.damping != Vec6{}) o.raw("damping", shared(damping_text, jt.damping.get()));
  static const char* axes[6] = {"x", "y", "z", "rx", "ry", "rz"};
  if (jt.tables.any())
    o.object("tables", [&](Object& tables) {
      for (std::size_t a = 0; a < 6; ++a)
        if (!jt.tables[a].empty())
          tables.object(axes[a], [&](Object& t) { t("deflection", jt.tables[a].deflection)("force", jt.tables[a].force); });
    });
  if (jt.preload != Vec6{}) o.raw("preload", shared(preload_text, jt.preload.get()));
}

void write_load(std::string& out, const Model& m, const Load& l) {
  Object o(out);
  o("body", m.bodies[static_cast<std::size_t>(l.body)].name)("force", l.force)("torque", l.torque);
  if (!zero(l.point)) o("point", l.point);
  if (l.body_frame) o("frame", "body");
  o.object("function", function_of(l.function));
  if (l.damping != Vec3{}) o("damping", l.damping);
  if (l.angular_damping != Vec6{}) o("angular_damping", l.angular_damping);
}

void write_driver(std::string& out, const Model& m, const Driver& d) {
  Object o(out);
  o("body", m.bodies[static_cast<std::size_t>(d.body)].name);
  o.object("motion", [&](Object& motion) {
    if (!zero(d.velocity)) motion("velocity", d.velocity);
    static const char* axes[3] = {"x", "y", "z"};
    for (std::size_t a = 0; a < 3; ++a)
      if (!is_zero_constant(d.displacement[a])) motion.object(axes[a], function_of(d.displacement[a]));
  });
}

// One body or joint per line: readable, and error line numbers stay meaningful. The text
// is written directly, item by item: no document of the model is ever built (a
// million-body model's document tree would take gigabytes). After each item, once out
// holds more than a megabyte, spill(out) takes it (and empties it), so that a file
// is written without the whole text in memory (a million-body grid's is 690 MB).
template <class Spill>
void write_model_json(const Model& m, std::string& out, Spill spill) {
  constexpr std::size_t spill_at = std::size_t{1} << 20;
  bool first_key = true;
  out += "{\n";
  auto key = [&](const char* k) {
    out += first_key ? "  " : ",\n  ";
    first_key = false;
    json_text::write(out, k);
    out += ": ";
  };
  auto list = [&](const char* k, const auto& items, const auto& write_item) {
    key(k);
    if (items.empty()) {
      out += "[]";
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < items.size(); ++i) {
      out += "    ";
      write_item(items[i]);
      out += i + 1 < items.size() ? ",\n" : "\n";
      if (out.size() > spill_at) spill(out);
    }
    out += "  ]";
  };
  key("name");
  json_text::write(out, m.name);
  key("gravity");
  json_text::write(out, m.gravity);
  SharedText shared;
  // A flexible body is written as its item (its file and placement) in its frame's place;
  // its node bodies come from the file, so they are not written. (A model without one, a
  // million bodies perhaps, is written straight from its list.)
  const auto body = [&](const Body& b) { write_body(out, b, shared); };
  if (m.flexible.empty()) {
    list("bodies", m.bodies, body);
  } else {
    std::vector<const std::string*> item_of(m.bodies.size(), nullptr);
    std::vector<char> node(m.bodies.size(), 0);
    for (const FlexibleBody& f : m.flexible) {
      item_of[static_cast<std::size_t>(f.frame)] = &f.source;
      for (int b : f.nodes) node[static_cast<std::size_t>(b)] = 1;
    }
    std::vector<std::size_t> written;
    for (std::size_t b = 0; b < m.bodies.size(); ++b)
      if (!node[b]) written.push_back(b);
    list("bodies", written, [&](std::size_t b) {
      if (item_of[b])
        out += *item_of[b];
      else
        body(m.bodies[b]);
    });
  }
  list("joints", m.joints, [&](const Joint& j) { write_joint(out, m, j, shared); });
  if (!m.loads.empty()) list("loads", m.loads, [&](const Load& l) { write_load(out, m, l); });
  if (!m.drivers.empty()) list("drivers", m.drivers, [&](const Driver& d) { write_driver(out, m, d); });
  const SimulationSettings& s = m.simulation;
  key("simulation");
  {
    Object sim(out);
    sim("t_start", s.t_start)("t_end", s.t_end);
    if (s.method) sim("method", method_name(*s.method));  // none: chosen at the run, as for the model read
    if (s.output_every) sim("output_every", *s.output_every);
    sim("rtol", s.rtol)("atol", s.atol);
    if (s.step) sim("step", *s.step);
    if (!s.variant.empty()) sim("variant", s.variant);
    if (s.output_interval) sim("output_interval", *s.output_interval);
    if (s.assemble) sim("assemble", true);
  }
  out += "\n}\n";
}

}  // namespace

std::string model_to_json(const Model& m) {
  std::string out;
  // About 250 characters per body and per joint; one reservation spares the copies of growth.
  out.reserve(1024 + 256 * (m.bodies.size() + m.joints.size()));
  write_model_json(m, out, [](std::string&) {});
  return out;
}

void write_model_file(const Model& model, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InputError(path + ": cannot write the model file");
  std::string text;
  auto spill = [&](std::string& t) {
    out.write(t.data(), static_cast<std::streamsize>(t.size()));
    t.clear();
  };
  write_model_json(model, text, spill);
  spill(text);
  if (!out) throw InputError(path + ": error while writing the model file");
}

}  // namespace mbsflow
