#include "mbsflow/io/model_reader.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "json_list_stream.hpp"
#include "json_depth.hpp"
#include "beam_reader.hpp"
#include "json_node.hpp"
#include "json_tape_list.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/file_text.hpp"
#include "mbsflow/io/reduced_part_file.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/run_request.hpp"
#include "mbsflow/runtime/run_settings.hpp"
#include "model_fields.hpp"
#include "model_reading.hpp"
#include "name_index.hpp"

namespace mbsflow {
namespace model_fields {

constexpr double unit_tolerance = 1e-6;  // allowed |norm - 1| of given quaternions

Vec3 vec3(const JsonNode& parent, const char* key, Vec3 fallback) {
  const auto n = parent.find(key);
  return n ? n->fixed<3>() : fallback;
}

Quat unit_quat(const JsonNode& n) {
  const auto q = n.fixed<4>();
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (std::abs(norm - 1.0) > unit_tolerance)
    n.fail("must be a unit quaternion [w, x, y, z] (norm " + number_text(norm) + ", allowed deviation 1e-6)");
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

TimeFunction time_function(const JsonNode& n) {
  if (n.is_string()) {
    if (n.string() != "constant") n.fail("must be \"constant\" or an object with a \"type\" (got '" + n.string() + "')");
    return TimeFunction::constant(1.0);
  }
  n.expect_object();
  const std::string type = n["type"].string();
  TimeFunction f;
  if (type == "constant") {
    n.allow_only({"type", "value", "delay"});
    f.value = n.find("value") ? n["value"].number() : 1.0;
  } else if (type == "harmonic") {
    n.allow_only({"type", "amplitude", "frequency", "phase", "offset", "delay"});
    f.kind = TimeFunction::Kind::harmonic;
    f.amplitude = n["amplitude"].number();
    f.frequency = n["frequency"].non_negative();
    f.phase = n.find("phase") ? n["phase"].number() : 0.0;
    f.offset = n.find("offset") ? n["offset"].number() : 0.0;
  } else if (type == "table") {
    n.allow_only({"type", "t", "value", "delay"});
    f.kind = TimeFunction::Kind::table;
    f.times = n["t"].numbers();
    f.values = n["value"].numbers();
    if (f.times.empty()) n["t"].fail("must not be empty");
    if (f.values.size() != f.times.size())
      n["value"].fail("must have as many numbers as t (" + std::to_string(f.times.size()) + ", got " +
                      std::to_string(f.values.size()) + ")");
    for (std::size_t i = 1; i < f.times.size(); ++i)
      if (!(f.times[i] > f.times[i - 1])) n["t"].item(i).fail("must be strictly increasing");
  } else if (type == "random") {
    n.allow_only({"type", "amplitude", "cutoff", "seed", "components", "delay"});
    f.kind = TimeFunction::Kind::random;
    f.amplitude = n["amplitude"].non_negative();
    f.cutoff = n["cutoff"].positive();
    f.seed = static_cast<std::uint64_t>(n.find("seed") ? n["seed"].integer(0) : 0);
    f.components = static_cast<int>(n.find("components") ? n["components"].integer(1, TimeFunction::max_components) : 32);
  } else {
    n["type"].fail("must be one of constant, harmonic, table, random (got '" + type + "')");
  }
  f.delay = n.find("delay") ? n["delay"].number() : 0.0;
  return f;
}

}  // namespace model_fields

namespace {
using namespace model_fields;

// Inertia: 3 principal moments or the 6 tensor entries; positive definite, and the
// principal moments must satisfy the triangle inequality (a real mass distribution).
Vec6 inertia(const JsonNode& n) {
  const std::vector<double> v = n.numbers();
  if (v.size() != 3 && v.size() != 6) n.fail("must have 3 or 6 numbers (got " + std::to_string(v.size()) + ")");
  Vec6 i{v[0], v[1], v[2], 0, 0, 0};
  if (v.size() == 6) i = {v[0], v[1], v[2], v[3], v[4], v[5]};
  Eigen::Vector3d e(i[0], i[1], i[2]);  // principal moments, ascending
  if (i[3] == 0.0 && i[4] == 0.0 && i[5] == 0.0) {  // principal axes already: no solver (a million bodies)
    std::sort(e.begin(), e.end());
  } else {
    Eigen::Matrix3d m;
    m << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
    e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
  }
  if (!(e[0] > 0.0)) n.fail("must be positive definite (smallest principal moment " + number_text(e[0]) + ")");
  if (e[0] + e[1] < e[2] * (1.0 - 1e-9))
    n.fail("principal moments " + number_text(e[0]) + ", " + number_text(e[1]) + ", " + number_text(e[2]) +
           " violate the triangle inequality");
  return i;
}

ForceTable force_table(const JsonNode& n) {
  n.allow_only({"deflection", "force"});
  ForceTable t{n["deflection"].numbers(), n["force"].numbers()};
  if (t.deflection.size() < 2) n["deflection"].fail("must have at least 2 points");
  if (t.force.size() != t.deflection.size())
    n["force"].fail("must have as many numbers as deflection (" + std::to_string(t.deflection.size()) + ", got " +
                    std::to_string(t.force.size()) + ")");
  for (std::size_t i = 1; i < t.deflection.size(); ++i)
    if (!(t.deflection[i] > t.deflection[i - 1])) n["deflection"].item(i).fail("must be strictly increasing");
  return t;
}

std::optional<JointType> kinematic_type(const std::string& name) {
  for (JointType t : {JointType::revolute, JointType::spherical, JointType::prismatic, JointType::cylindrical,
                      JointType::universal, JointType::planar, JointType::fixed, JointType::distance,
                      JointType::screw})
    if (name == joint_type_name(t)) return t;
  return std::nullopt;
}

// The names a NameIndex compares with: those of the bodies or joints read so far.
template <class Item>
struct NamesOf {
  const std::vector<Item>& items;
  std::string_view operator()(int i) const { return items[static_cast<std::size_t>(i)].name; }
};

// Reads a model as its text is parsed: each body, joint, load and driver as soon as it
// is complete (joints, loads and drivers listed before the bodies wait for them), then
// the rest of the document.
class Reader {
 public:
  enum List : std::size_t { bodies_list, joints_list, loads_list, drivers_list, list_count };
  static constexpr std::array<const char*, list_count> list_names{"bodies", "joints", "loads", "drivers"};

  explicit Reader(const JsonSource& src) : src_(src) {}

  // The reference reader's lists: these, then "beams" (index beams_list).
  static constexpr std::size_t beams_list = list_count;
  static constexpr const char* beams_name = "beams";

  // A model that may have beams (its text holds "beams"): joints, loads and drivers wait
  // for them too, since they may name a beam's nodes.
  void expect_beams(bool maybe) { expect_beams_ = maybe; }

  void item(std::size_t list, std::size_t index, nlohmann::json&& j) {
    if (list == bodies_list)
      body(JsonNode(j, item_path(list_names[list], index), src_));
    else if (list == beams_list && bodies_read_)
      beam(JsonNode(j, item_path(beams_name, index), src_));
    else if (list == beams_list)  // a beam's nodes come after the bodies, whatever the order in the file
      waiting_beams_.push_back(std::move(j));
    else if (ready())
      dependent(list, JsonNode(j, item_path(list_names[list], index), src_));
    else
      waiting_[list].push_back(std::move(j));
  }
  // The fast reader's items (read_model_fast), which comes to a list of joints, loads or
  // drivers only once the bodies are read. A body or joint is made from its tape first, on
  // any thread and beside others (reading only the bodies), then taken into the model in
  // the list's order, where its name is checked against those before it. (The reference
  // reader checks the name before the rest; the fast reader gives up at any error, so
  // which error comes first does not matter to it.)
  Body fast_body(std::size_t index, const JsonTape& tape) const {
    return make_body(JsonNode(tape, list_names[bodies_list], index, src_), [](const std::string&, const JsonNode&) {});
  }
  Joint fast_joint(std::size_t index, const JsonTape& tape) const {
    return make_joint(JsonNode(tape, list_names[joints_list], index, src_), index, [](const std::string&, const JsonNode&) {});
  }
  void take_body(std::size_t index, const JsonTape& tape, Body&& b) {
    enter_body_name(b.name, JsonNode(tape, list_names[bodies_list], index, src_)["name"]);
    shared_(b);
    m_.bodies.push_back(std::move(b));
  }
  void take_joint(std::size_t index, const JsonTape& tape, Joint&& j) {
    enter_joint_name(j.name, JsonNode(tape, list_names[joints_list], index, src_));
    shared_(j);
    m_.joints.push_back(std::move(j));
  }
  // A load or a driver, read at once.
  void item(std::size_t list, std::size_t index, const JsonTape& tape) { dependent(list, JsonNode(tape, list_names[list], index, src_)); }

  void end(std::size_t list, std::size_t count) {
    if (list == beams_list) {
      beams_read_ = true;
      release();
      return;
    }
    if (list != bodies_list) return;
    if (count == 0 && !expect_beams_) JsonNode(nlohmann::json::array(), list_names[list], src_).fail("must list at least one body");
    bodies_read_ = true;
    // Most models have about as many joints as bodies: room for them now spares the moves
    // and page faults of growing by doubling (a Joint is large). Pages that stay unused
    // are never touched, so a model with fewer joints costs only address space.
    m_.joints.reserve(m_.bodies.size());
    for (std::size_t i = 0; i < waiting_beams_.size(); ++i) beam(JsonNode(waiting_beams_[i], item_path(beams_name, i), src_));
    waiting_beams_.clear();
    release();
  }

  // Room for at most n items of a list, made before it is read (read_model_fast).
  void expect(std::size_t list, std::size_t n) {
    if (list == bodies_list) m_.bodies.reserve(n);
    if (list == joints_list) m_.joints.reserve(n);
  }

  // The document less the streamed lists.
  Model finish(const nlohmann::json& document) {
    const JsonNode root(document, "", src_);
    root.allow_only({"name", "description", "gravity", "bodies", "joints", "loads", "drivers", "simulation", "beams"});
    if (expect_beams_ && !(bodies_read_ && beams_read_)) {  // no beams after all, or no bodies besides them
      if (!bodies_read_ && !root.find("bodies")) end(bodies_list, 0);
      beams_read_ = true;
      release();
    }
    if (auto n = root.find("name")) m_.name = n->string();
    if (auto n = root.find("description")) n->string();
    m_.gravity = vec3(root, "gravity");
    // A streamed list is left as an empty array; one that was not streamed is missing or
    // not an array, and fails here as it should.
    if (m_.beams.empty() || root.find(list_names[bodies_list])) root[list_names[bodies_list]].array_size();
    if (m_.bodies.empty()) JsonNode(nlohmann::json::array(), list_names[bodies_list], src_).fail("must list at least one body (or a beam)");
    if (auto n = root.find(beams_name)) n->array_size();
    for (std::size_t l = joints_list; l < list_count; ++l)
      if (auto n = root.find(list_names[l])) n->array_size();
    if (auto n = root.find("simulation")) simulation(*n);
    return std::move(m_);
  }

 private:
  void dependent(std::size_t list, const JsonNode& n) {
    if (list == joints_list)
      joint(n);
    else if (list == loads_list)
      load(n);
    else
      driver(n);
  }

  // Joints, loads and drivers can be read once the bodies are, and the beams if any.
  bool ready() const { return bodies_read_ && (!expect_beams_ || beams_read_); }

  void release() {
    if (!ready()) return;
    for (std::size_t l = joints_list; l < list_count; ++l) {
      for (std::size_t i = 0; i < waiting_[l].size(); ++i) dependent(l, JsonNode(waiting_[l][i], item_path(list_names[l], i), src_));
      waiting_[l].clear();
    }
  }

  void beam(const JsonNode& n) {
    std::string name;
    BeamParts parts = read_beam(n, static_cast<int>(m_.bodies.size()), name);
    BeamRecord r{name, static_cast<int>(m_.bodies.size()), static_cast<int>(parts.nodes.size()),
                 static_cast<int>(m_.joints.size()), static_cast<int>(parts.elements.size())};
    for (Body& b : parts.nodes) {
      enter_body_name(b.name, n["name"]);
      shared_(b);
      m_.bodies.push_back(std::move(b));
    }
    for (Joint& j : parts.elements) {
      enter_joint_name(j.name, n);
      shared_(j);
      m_.joints.push_back(std::move(j));
    }
    m_.loads.insert(m_.loads.end(), parts.loads.begin(), parts.loads.end());
    m_.beams.push_back(std::move(r));
  }

  void body(const JsonNode& n) {
    if (auto type = n.find("type")) {
      if (type->string() != "flexible") type->fail("must be \"flexible\" (a rigid body has no type)");
      flexible(n);
      return;
    }
    m_.bodies.push_back(make_body(n, [&](const std::string& name, const JsonNode& at) { enter_body_name(name, at); }));
    shared_(m_.bodies.back());
  }

  // A reduced FE part on a floating frame (flexible_body.hpp): its frame body, then a body
  // per interface node, "NAME@ID".
  void flexible(const JsonNode& n) {
    n.allow_only({"name", "type", "file", "position", "orientation", "velocity", "angular_velocity", "damping",
                  "modal_coordinates", "modal_rates"});
    FlexibleBody f;
    const JsonNode name = n["name"];
    f.name = name.string();
    if (f.name.empty() || f.name == "ground" || f.name.find('@') != std::string::npos)
      name.fail("must be a name other than ground, without '@'");
    std::filesystem::path file = n["file"].string();
    if (file.is_relative()) file = std::filesystem::path(src_.file).parent_path() / file;
    file = std::filesystem::absolute(file).lexically_normal();
    ReducedPart part;
    try {
      part = read_reduced_part(file.string());
    } catch (const InputError& e) {
      n["file"].fail(e.text());
    }
    const int ne = part.floating.modes();
    if (ne == 0)
      n["file"].fail(file.string() + " has no floating frame: it has " + std::to_string(part.mass.rows()) +
                     " reduced coordinates, and a flexible body takes at most " + std::to_string(max_floating_modes + 6) +
                     " (reduce it with fewer interface nodes, --rigid-face for a face, or fewer --modes)");
    f.data = std::make_shared<const FloatingFrameData>(std::move(part.floating));
    const FloatingFrameData& d = *f.data;
    const Vec3 origin = vec3(n, "position");
    Quat orientation{1.0, 0.0, 0.0, 0.0};
    if (auto q = n.find("orientation")) orientation = unit_quat(*q);
    const Eigen::Quaterniond rq(orientation[0], orientation[1], orientation[2], orientation[3]);
    const Eigen::Matrix3d r = rq.normalized().toRotationMatrix();
    const Vec3 velocity = vec3(n, "velocity"), spin = vec3(n, "angular_velocity");
    const Eigen::Vector3d v(velocity[0], velocity[1], velocity[2]), w(spin[0], spin[1], spin[2]);
    const Eigen::Vector3d centre = Eigen::Vector3d(origin[0], origin[1], origin[2]) + r * d.centre;
    auto to_vec3 = [](const Eigen::Vector3d& x) { return Vec3{x.x(), x.y(), x.z()}; };
    const auto nodes = static_cast<double>(d.node_id.size());
    auto make = [&](const std::string& body_name, double mass, const Eigen::Matrix3d& inertia, const Eigen::Vector3d& arm) {
      Body b;
      b.name = body_name;
      enter_body_name(b.name, name);
      b.mass = mass;
      b.inertia = Vec6{inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
      b.position = to_vec3(centre + r * arm);
      b.orientation = orientation;
      b.velocity = to_vec3(v + r * w.cross(arm));
      b.angular_velocity = spin;
      shared_(b);
      m_.bodies.push_back(std::move(b));
      return static_cast<int>(m_.bodies.size()) - 1;
    };
    f.frame = make(f.name, d.mass, d.inertia, Eigen::Vector3d::Zero());
    // The nodes' masses and inertias serve the stable-step estimates only (a share of the part's).
    for (std::size_t k = 0; k < d.node_id.size(); ++k)
      f.nodes.push_back(make(f.name + "@" + std::to_string(d.node_id[k]), d.mass / nodes, d.inertia / nodes, d.node_position[k]));
    nlohmann::json item = {{"name", f.name}, {"type", "flexible"}, {"file", file.string()}, {"position", origin},
                           {"orientation", orientation}, {"velocity", velocity}, {"angular_velocity", spin}};
    f.damping = Eigen::VectorXd::Zero(ne);
    if (auto damping = n.find("damping")) {
      damping->allow_only({"ratio", "alpha", "beta"});
      const double ratio = damping->find("ratio") ? (*damping)["ratio"].non_negative() : 0.0;
      const double alpha = damping->find("alpha") ? (*damping)["alpha"].non_negative() : 0.0;
      const double beta = damping->find("beta") ? (*damping)["beta"].non_negative() : 0.0;
      for (int k = 0; k < ne; ++k) f.damping[k] = 2.0 * ratio * std::sqrt(d.omega2[k]) + alpha + beta * d.omega2[k];
      item["damping"] = {{"ratio", ratio}, {"alpha", alpha}, {"beta", beta}};
    }
    // The initial deformation and its rate, by modal coordinate (the first ones given, the
    // rest zero).
    for (const char* key : {"modal_coordinates", "modal_rates"})
      if (auto given = n.find(key)) {
        const std::vector<double> values = given->numbers();
        if (values.size() > static_cast<std::size_t>(ne))
          given->fail("has " + std::to_string(values.size()) + " values; the part has " + std::to_string(ne) + " modes");
        Eigen::VectorXd& to = key[6] == 'c' ? f.initial_eta : f.initial_eta_rate;
        to = Eigen::VectorXd::Zero(ne);
        std::copy(values.begin(), values.end(), to.data());
        item[key] = values;
      }
    f.source = item.dump();
    m_.flexible.push_back(std::move(f));
  }

  // The body n describes; enter_name(name, node) is called where the reference reader
  // checks the name against those before it.
  template <class EnterName>
  Body make_body(const JsonNode& n, EnterName enter_name) const {
    n.allow_only({"name", "mass", "inertia", "position", "orientation", "velocity", "angular_velocity"});
    Body b;
    const JsonNode name = n["name"];
    b.name = name.string();
    if (b.name.empty()) name.fail("must not be empty");
    if (b.name == "ground") name.fail("'ground' is reserved for the fixed world frame");
    enter_name(b.name, name);
    b.mass = n["mass"].positive();
    b.inertia = inertia(n["inertia"]);
    b.position = vec3(n, "position");
    if (auto q = n.find("orientation")) b.orientation = unit_quat(*q);
    b.velocity = vec3(n, "velocity");
    b.angular_velocity = vec3(n, "angular_velocity");
    return b;
  }

  // Enters the name of the body about to be added; at: its "name" node, for the message.
  void enter_body_name(const std::string& name, const JsonNode& at) {
    if (const int first = body_index_.insert(name, static_cast<int>(m_.bodies.size()), NamesOf<Body>{m_.bodies}); first >= 0)
      at.fail("duplicate body name '" + name + "' (first at " + item_path(list_names[bodies_list], static_cast<std::size_t>(first)) + ")");
  }

  int body_ref(const JsonNode& n, bool ground_ok) const {
    const std::string name = n.string();
    if (name == "ground") {
      if (!ground_ok) n.fail("must name a body, not ground");
      return ground;
    }
    const int body = body_index_.find(name, NamesOf<Body>{m_.bodies});
    if (body < 0) n.fail("unknown body '" + name + "'");
    return body;
  }

  void joint(const JsonNode& n) {
    m_.joints.push_back(make_joint(n, m_.joints.size(), [&](const std::string& name, const JsonNode& at) { enter_joint_name(name, at); }));
    shared_(m_.joints.back());
  }

  // The joint n describes, the index-th of its list; enter_name as for make_body (at: the
  // joint's node).
  template <class EnterName>
  Joint make_joint(const JsonNode& n, std::size_t index, EnterName enter_name) const {
    n.expect_object();
    const JsonNode type = n["type"];
    const std::string t = type.string();
    Joint j;
    if (t == "bushing") {
      n.allow_only({"name", "type", "body1", "body2", "point1", "point2", "frame1", "frame2", "stiffness", "damping",
                    "frequency", "damping_ratio", "tables", "preload"});
    } else if (t == "spring") {
      n.allow_only({"name", "type", "body1", "body2", "point1", "point2", "stiffness", "damping", "rest_length"});
      j.type = JointType::spring;
    } else if (const auto k = kinematic_type(t)) {
      j.type = *k;
    } else {
      type.fail("must be one of bushing, spring, revolute, spherical, prismatic, cylindrical, universal, planar, fixed, "
                "distance, screw (got '" + t + "')");
    }
    j.name = n.find("name") ? n["name"].string() : "j" + std::to_string(index);
    enter_name(j.name, n);
    j.body1 = body_ref(n["body1"], true);
    j.body2 = body_ref(n["body2"], false);
    if (j.body1 == j.body2) n["body2"].fail("joins body '" + m_.bodies[static_cast<std::size_t>(j.body2)].name + "' to itself");
    j.point1 = vec3(n, "point1");
    j.point2 = vec3(n, "point2");
    if (j.type == JointType::spring)
      spring(n, j);
    else if (j.type == JointType::bushing)
      bushing(n, j);
    else
      read_kinematic_joint(n, m_, j);
    return j;
  }

  // Enters the name of the joint about to be added; at: the joint's node.
  void enter_joint_name(const std::string& name, const JsonNode& at) {
    if (const int first = joint_index_.insert(name, static_cast<int>(m_.joints.size()), NamesOf<Joint>{m_.joints}); first >= 0)
      (at.find("name") ? at["name"] : at).fail("duplicate joint name '" + name + "' (first at " + item_path("joints", static_cast<std::size_t>(first)) + ")");
  }

  void spring(const JsonNode& n, Joint& j) const {
    j.stiffness.set(0, n["stiffness"].non_negative());
    j.damping.set(0, n.find("damping") ? n["damping"].non_negative() : 0.0);
    if (auto l = n.find("rest_length")) {
      j.rest_length = l->non_negative();
    } else {  // default: the initial distance of the two points
      const Body* b1 = j.body1 == ground ? nullptr : &m_.bodies[static_cast<std::size_t>(j.body1)];
      const Body& b2 = m_.bodies[static_cast<std::size_t>(j.body2)];
      Eigen::Vector3d p1(j.point1[0], j.point1[1], j.point1[2]);
      if (b1) p1 = world_point(*b1, j.point1);
      j.rest_length = (world_point(b2, j.point2) - p1).norm();
    }
  }

  static Eigen::Vector3d world_point(const Body& b, const Vec3& p) {
    const Eigen::Quaterniond q(b.orientation[0], b.orientation[1], b.orientation[2], b.orientation[3]);
    return Eigen::Vector3d(b.position[0], b.position[1], b.position[2]) + q.normalized() * Eigen::Vector3d(p[0], p[1], p[2]);
  }

  void bushing(const JsonNode& n, Joint& j) const {
    const bool by_stiffness = n.has("stiffness"), by_frequency = n.has("frequency");
    if (by_stiffness && by_frequency) n["frequency"].fail_at_key("give either stiffness/damping or frequency/damping_ratio, not both");
    if (n.has("damping_ratio") && !by_frequency) n["damping_ratio"].fail_at_key("needs 'frequency'");
    if (n.has("damping") && by_frequency) n["damping"].fail_at_key("give either stiffness/damping or frequency/damping_ratio, not both");
    if (auto f = n.find("frame1")) j.frame1 = unit_quat(*f);
    j.frame2 = n.find("frame2") ? unit_quat(n["frame2"]) : rest_frame2(m_, j);
    if (by_frequency) {
      const double mu = n.find("damping_ratio") ? n["damping_ratio"].non_negative() : 0.0;
      set_bushing_from_frequency(m_, j, n["frequency"].positive(), mu);
    } else if (by_stiffness) {
      j.stiffness = six_non_negative(n["stiffness"]);
      if (auto d = n.find("damping")) j.damping = six_non_negative(*d);
    } else if (!n.has("tables")) {
      n.fail("missing field 'stiffness' (or 'frequency', or 'tables')");
    }
    if (auto t = n.find("tables")) {
      static const char* axes[6] = {"x", "y", "z", "rx", "ry", "rz"};
      t->allow_only({"x", "y", "z", "rx", "ry", "rz"});
      for (std::size_t a = 0; a < 6; ++a)
        if (auto axis = t->find(axes[a])) j.tables[a] = force_table(*axis);
    }
    if (auto p = n.find("preload")) j.preload = p->fixed<6>();
  }

  static Vec6 six_non_negative(const JsonNode& n) {
    const Vec6 v = n.fixed<6>();
    for (std::size_t i = 0; i < 6; ++i)
      if (v[i] < 0.0) n.item(i).non_negative();  // fails, naming the item
    return v;
  }

  void load(const JsonNode& n) {
    n.allow_only({"body", "force", "torque", "point", "frame", "function", "damping", "angular_damping"});
    Load l;
    l.body = body_ref(n["body"], false);
    l.force = vec3(n, "force");
    l.torque = vec3(n, "torque");
    l.point = vec3(n, "point");
    if (auto d = n.find("damping")) {
      l.damping = d->fixed<3>();
      for (std::size_t i = 0; i < 3; ++i)
        if (l.damping[i] < 0.0) d->item(i).non_negative();  // fails, naming the item
    }
    if (auto d = n.find("angular_damping")) {
      l.angular_damping = d->fixed<6>();
      for (std::size_t i = 0; i < 3; ++i)
        if (l.angular_damping[i] < 0.0) d->item(i).non_negative();
    }
    if (auto f = n.find("frame")) {
      const std::string frame = f->string();
      if (frame != "world" && frame != "body") f->fail("must be \"world\" or \"body\" (got '" + frame + "')");
      l.body_frame = frame == "body";
    }
    if (auto f = n.find("function")) l.function = time_function(*f);
    m_.loads.push_back(l);
  }

  void driver(const JsonNode& n) {
    n.allow_only({"body", "motion"});
    Driver d;
    const JsonNode body = n["body"];
    d.body = body_ref(body, false);
    for (const Driver& other : m_.drivers)
      if (other.body == d.body) body.fail("body '" + body.string() + "' already has a driver");
    const JsonNode motion = n["motion"];
    motion.allow_only({"velocity", "x", "y", "z"});
    d.velocity = vec3(motion, "velocity");
    static const char* axes[3] = {"x", "y", "z"};
    for (std::size_t a = 0; a < 3; ++a)
      if (auto f = motion.find(axes[a])) d.displacement[a] = time_function(*f);
    m_.drivers.push_back(d);
  }

  // The block's fields are the settings declared in_model (run_settings.hpp), each read
  // and checked as declared, then applied as a run's settings are.
  void simulation(const JsonNode& n) {
    static const std::vector<const char*> keys = [] {
      std::vector<const char*> k;
      for (const RunSetting& s : run_settings())
        if (s.places & in_model) k.push_back(s.name);
      return k;
    }();
    n.allow_only(keys);
    RunRequest r;
    for (const RunSetting& s : run_settings())
      if (s.places & in_model)
        if (auto v = n.find(s.name)) read_setting(*v, s, r);
    const double t_start = r.t_start.value_or(m_.simulation.t_start);
    if (auto v = n.find("t_end"); v && !(*r.t_end > t_start))
      v->fail("must be > t_start (" + number_text(t_start) + ", got " + number_text(*r.t_end) + ")");
    apply_overrides(m_, r);
  }

  static void read_setting(const JsonNode& v, const RunSetting& s, RunRequest& r) {
    struct Read {
      const JsonNode& v;
      const RunSetting& s;
      std::string got;
      bool flag() const { return v.boolean(); }
      double number() {
        const double x = v.number();
        got = number_text(x);
        return x;
      }
      std::string text() {
        std::string t = v.string();
        got = "'" + t + "'";
        return t;
      }
      [[noreturn]] void fail(const std::string& what) const {
        if (s.allowed().empty()) v.fail(what + " (got " + got + ")");
        std::string list;  // the model format's own words for a choice
        for (const std::string& c : s.allowed()) list += (list.empty() ? "" : ", ") + c;
        v.fail("must be one of " + list + " (got " + got + ")");
      }
    };
    set_setting(s, r, Read{v, s, {}});
  }

  const JsonSource& src_;
  Model m_;
  ValueSharing shared_;  // repeated values of joints and bodies stored once
  bool bodies_read_ = false;
  bool expect_beams_ = false, beams_read_ = false;
  std::array<std::vector<nlohmann::json>, list_count> waiting_;
  std::vector<nlohmann::json> waiting_beams_;
  // Names to indices, so that each reference is found in constant time (a model of a
  // million bodies names as many in its joints).
  NameIndex body_index_, joint_index_;
};

// Where the JSON value at text[pos] ends, by its first character and, for strings and
// containers, quotes and brackets; npos if the text ends first. Not a check: nlohmann
// parses what this delimits.
std::size_t value_end(std::string_view text, std::size_t pos) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = pos; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"' && (in_string = false, depth == 0))
        return i + 1;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if (c == '}' || c == ']') {
      if (depth == 0) return i;  // a scalar's end
      if (--depth == 0) return i + 1;
    } else if (depth == 0 && (c == ',' || c == ' ' || c == '\n' || c == '\r' || c == '\t')) {
      return i;
    }
  }
  return depth == 0 && !in_string ? text.size() : std::string_view::npos;
}

// The record of an item that is read as it is taken (a load, a driver) or not at all.
struct Skipped {};

// How many times c occurs in text. memchr, not std::count: on the grid's 687 MB it took
// 0.03 s, std::count 0.23 s.
std::size_t count_of(char c, std::string_view text) {
  std::size_t n = 0;
  for (const char *p = text.data(), *end = p + text.size(); (p = static_cast<const char*>(std::memchr(p, c, static_cast<std::size_t>(end - p)))); ++p)
    ++n;
  return n;
}

// The model read by the fast reader (json_tape.hpp): the lists' items straight from the
// text, the rest of the document (a few small members) by nlohmann. nullopt where the text
// is outside the fast reader's subset or the model has an error: read_model_text then
// reads it again the slow way, whose checks and messages are the reference.
std::optional<Model> read_model_fast(std::string_view text, const JsonSource& src) try {
  constexpr std::size_t npos = std::string_view::npos;
  if (text.find("\"beams\"") != npos) return std::nullopt;  // beams: the reference reader
  if (text.find("\"flexible\"") != npos) return std::nullopt;  // flexible bodies too
  Reader reader(src);
  nlohmann::json rest = nlohmann::json::object();
  std::vector<std::string_view> keys;
  std::array<std::size_t, Reader::list_count> deferred;  // lists before the bodies: their '['
  deferred.fill(npos);
  bool bodies_read = false;
  constexpr int item_depth = max_json_depth - 2;  // inside the document and the list
  auto read_list = [&](std::size_t list, std::size_t pos) {
    // Each item of a list is an object, so the braces that follow bound their number: the
    // bodies and joints get room for that many first. Growing by doubling instead would
    // move and touch a million large records again and again; room never used is only
    // address space.
    if (list == Reader::bodies_list || list == Reader::joints_list) reader.expect(list, count_of('{', text.substr(pos)));
    std::size_t count = 0;
    auto counted = [&](std::size_t index) { count = index + 1; };
    if (list == Reader::bodies_list)
      pos = read_tape_list<Body>(
          text, pos, item_depth, [&](std::size_t i, const JsonTape& t) { return reader.fast_body(i, t); },
          [&](std::size_t i, const JsonTape& t, Body&& b) {
            reader.take_body(i, t, std::move(b));
            counted(i);
          });
    else if (list == Reader::joints_list)
      pos = read_tape_list<Joint>(
          text, pos, item_depth, [&](std::size_t i, const JsonTape& t) { return reader.fast_joint(i, t); },
          [&](std::size_t i, const JsonTape& t, Joint&& j) {
            reader.take_joint(i, t, std::move(j));
            counted(i);
          });
    else
      pos = read_tape_list<Skipped>(
          text, pos, item_depth, [](std::size_t, const JsonTape&) { return Skipped{}; },
          [&](std::size_t i, const JsonTape& t, Skipped&&) {
            reader.item(list, i, t);
            counted(i);
          });
    if (pos != npos) reader.end(list, count);
    return pos;
  };
  std::size_t pos = skip_json_space(text, 0);
  if (pos >= text.size() || text[pos] != '{') return std::nullopt;
  pos = skip_json_space(text, pos + 1);
  while (true) {
    std::string_view key;
    pos = parse_plain_json_string(text, pos, key);
    if (pos == npos || std::find(keys.begin(), keys.end(), key) != keys.end()) return std::nullopt;
    keys.push_back(key);
    pos = skip_json_space(text, pos);
    if (pos >= text.size() || text[pos] != ':') return std::nullopt;
    pos = skip_json_space(text, pos + 1);
    const auto list = std::find(Reader::list_names.begin(), Reader::list_names.end(), key);
    if (list != Reader::list_names.end() && pos < text.size() && text[pos] == '[') {
      const auto l = static_cast<std::size_t>(list - Reader::list_names.begin());
      rest[std::string(key)] = nlohmann::json::array();
      if (l != Reader::bodies_list && !bodies_read) {
        deferred[l] = pos;
        pos = read_tape_list<Skipped>(
            text, pos, item_depth, [](std::size_t, const JsonTape&) { return Skipped{}; }, [](std::size_t, const JsonTape&, Skipped&&) {});
      } else {
        pos = read_list(l, pos);
      }
      if (l == Reader::bodies_list && pos != npos) {
        bodies_read = true;
        for (std::size_t d = Reader::joints_list; d < Reader::list_count; ++d)
          if (deferred[d] != npos && read_list(d, deferred[d]) == npos) return std::nullopt;
      }
    } else {
      const std::size_t end = value_end(text, pos);
      if (end == npos || json_too_deep(text.substr(pos, end - pos), max_json_depth - 1) != npos) return std::nullopt;
      rest[std::string(key)] = nlohmann::json::parse(text.substr(pos, end - pos));
      pos = end;
    }
    if (pos == npos) return std::nullopt;
    pos = skip_json_space(text, pos);
    if (pos >= text.size()) return std::nullopt;
    if (text[pos] == '}') break;
    if (text[pos] != ',') return std::nullopt;
    pos = skip_json_space(text, pos + 1);
  }
  if (skip_json_space(text, pos + 1) != text.size() || !bodies_read) return std::nullopt;
  return reader.finish(rest);
} catch (const InputError&) {
  return std::nullopt;
} catch (const nlohmann::json::exception&) {
  return std::nullopt;
}

}  // namespace

std::optional<Model> read_model_fast(std::string_view text, const std::string& name) {
  return read_model_fast(text, JsonSource{name, JsonLocations(text)});
}

Model read_model_reference(std::string_view text, const std::string& name) {
  const JsonSource src{name, JsonLocations(text)};
  Reader reader(src);
  reader.expect_beams(text.find("\"beams\"") != std::string_view::npos);
  JsonListHandlers lists;
  lists.lists.assign(Reader::list_names.begin(), Reader::list_names.end());
  lists.lists.push_back(Reader::beams_name);
  lists.item = [&](std::size_t list, std::size_t i, nlohmann::json&& item) { reader.item(list, i, std::move(item)); };
  lists.end = [&](std::size_t list, std::size_t count) { reader.end(list, count); };
  return reader.finish(parse_json_streaming_lists(text, name, lists));
}

Model read_model_text(std::string_view text, const std::string& name) {
  if (std::optional<Model> m = read_model_fast(text, name)) return std::move(*m);
  return read_model_reference(text, name);
}

std::string read_model_file_text(const std::string& path) { return read_input_file(path, "model file", max_model_bytes); }

Model read_model_file(const std::string& path) {
  const FileText file = map_model_file(path);
  return read_model_text(file.text(), path);
}

}  // namespace mbsflow
