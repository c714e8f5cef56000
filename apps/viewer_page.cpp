#include "viewer_page.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <nlohmann/json.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/io/mode_frames.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "shared_files.hpp"

namespace mbsflow::cli {
namespace {

std::string base64(const std::vector<float>& v) {
  static constexpr char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = reinterpret_cast<const unsigned char*>(v.data());
  const std::size_t n = v.size() * sizeof(float);
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned x = b[i] << 16 | (i + 1 < n ? b[i + 1] << 8 : 0) | (i + 2 < n ? b[i + 2] : 0);
    out += digits[x >> 18 & 63];
    out += digits[x >> 12 & 63];
    out += i + 1 < n ? digits[x >> 6 & 63] : '=';
    out += i + 2 < n ? digits[x & 63] : '=';
  }
  return out;
}

void replace(std::string& page, const std::string& mark, const std::string& text) {
  const std::size_t at = page.find(mark);
  if (at == std::string::npos) throw Error("mbsflow view: the page template lacks " + mark);
  page.replace(at, mark.size(), text);
}

// Semi-axes of the uniform ellipsoid with the body's mass and (diagonal) inertia: the
// shape drawn. Bodies without a usable inertia get a sphere of `fallback`.
Eigen::Vector3d ellipsoid(const Body& b, double fallback) {
  const double ix = b.inertia[0], iy = b.inertia[1], iz = b.inertia[2];
  const Eigen::Vector3d squared = 2.5 / b.mass * Eigen::Vector3d(iy + iz - ix, ix + iz - iy, ix + iy - iz);
  if (!(b.mass > 0) || !(squared.minCoeff() > 0) || !squared.allFinite()) return Eigen::Vector3d::Constant(fallback);
  return squared.cwiseSqrt();
}

// The motion to show: frames of body positions and orientations, joint points, and the
// quantities that colour the bodies.
struct Motion {
  std::size_t bodies = 0, joints = 0;
  std::vector<double> times;
  std::vector<std::size_t> rows;  // of a run's results: the snapshot of each frame
  std::vector<float> position, quaternion, attachment, speed, angular_speed, kinetic;
  bool orientation = false;
};

void append(std::vector<float>& to, const std::vector<double>& from) { to.insert(to.end(), from.begin(), from.end()); }

// A run's snapshots, evenly spread with the last included, within the data budget.
Motion run_motion(const ResultsFile& r, const ViewerSettings& s, ViewerPage& page) {
  if (!r.has("/bodies/position")) throw InputError(r.path() + ": no body positions to show (run with --fields position)");
  const std::vector<double> t = r.time();
  const std::size_t rows = std::min<std::size_t>(t.size(), r.shape("/bodies/position")[0]);
  if (rows == 0) throw InputError(r.path() + ": no snapshots yet");
  Motion m;
  m.bodies = r.body_names().size();
  const std::size_t n = m.bodies;
  m.orientation = r.has("/bodies/orientation");
  const bool velocity = r.has("/bodies/velocity");
  const bool spin = r.has("/bodies/angular_velocity"), ends = r.has(joint_attachment_dataset);
  const bool energies = r.has(body_energy_dataset);
  m.joints = ends ? r.shape(joint_attachment_dataset)[1] : 0;
  const double frame_bytes = 4.0 * (static_cast<double>(n) * (3 + 4 + 3) + 6.0 * static_cast<double>(m.joints));
  const auto budget = static_cast<std::size_t>(std::max(1.0, s.max_megabytes * 1e6 / frame_bytes));
  const std::size_t most = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(s.max_frames), budget));
  const std::vector<std::size_t> picked = evenly_spread_rows(rows, most);
  page.frames = static_cast<long>(picked.size());
  page.stride = picked.size() > 1 ? static_cast<long>(picked[1] - picked[0]) : 1;
  m.rows = picked;
  for (std::size_t k : picked) {
    m.times.push_back(t[k]);
    append(m.position, r.read_row("/bodies/position", k));
    if (m.orientation) append(m.quaternion, r.read_row("/bodies/orientation", k));
    if (ends) append(m.attachment, r.read_row(joint_attachment_dataset, k));
    const std::vector<double> v = velocity ? r.read_row("/bodies/velocity", k) : std::vector<double>{};
    const std::vector<double> w = spin ? r.read_row("/bodies/angular_velocity", k) : std::vector<double>{};
    const std::vector<double> e = energies ? r.read_row(body_energy_dataset, k) : std::vector<double>{};
    for (std::size_t i = 0; i < n; ++i) {
      if (velocity) m.speed.push_back(static_cast<float>(Eigen::Vector3d(v[3 * i], v[3 * i + 1], v[3 * i + 2]).norm()));
      if (spin) m.angular_speed.push_back(static_cast<float>(Eigen::Vector3d(w[3 * i], w[3 * i + 1], w[3 * i + 2]).norm()));
      if (energies) m.kinetic.push_back(static_cast<float>(e[2 * i]));
    }
  }
  return m;
}

// One mode of a modes file over one period (times in seconds; 1 s for a rigid-body motion),
// drawn as the XDMF sidecar draws it (mode_frames.hpp), coloured by each body's share of the
// mode's kinetic energy.
Motion mode_motion(const ResultsFile& r, const ViewerSettings& s, ViewerPage& page) {
  const std::vector<double> frequency = r.read("/modes/frequency");
  if (s.mode < 1 || static_cast<std::size_t>(s.mode) > frequency.size())
    throw InputError("--mode " + std::to_string(s.mode) + ": " + r.path() + " holds modes 1 to " + std::to_string(frequency.size()));
  const auto k = static_cast<std::size_t>(s.mode - 1);
  Motion m;
  m.bodies = r.body_names().size();
  m.orientation = true;
  const std::vector<double> rest = r.read("/equilibrium/position"), rest_q = r.read("/equilibrium/orientation");
  const std::vector<double> re = r.read_row("/modes/shape", k), im = r.read_row("/modes/shape_imag", k);
  const std::vector<double> share = r.read_row("/modes/energy_share", k);
  const auto shape = [&](std::size_t b, int e) { return std::complex<double>(re[6 * b + e], im[6 * b + e]); };
  const double scale = mode_scale(shape, m.bodies, model_size(rest));
  const int frames = static_cast<int>(std::clamp<long>(s.max_frames, 1, 48));
  const double period = frequency[k] > 0.0 ? 1.0 / frequency[k] : 1.0;
  std::vector<double> position(3 * m.bodies), quaternion(4 * m.bodies);
  for (int f = 0; f < frames; ++f) {
    const double phase = 2.0 * std::numbers::pi * f / frames;
    for (std::size_t b = 0; b < m.bodies; ++b)
      mode_frame_body(shape, b, scale, phase, &rest[3 * b], &rest_q[4 * b], &position[3 * b], &quaternion[4 * b]);
    m.times.push_back(period * f / frames);
    append(m.position, position);
    append(m.quaternion, quaternion);
    for (std::size_t b = 0; b < m.bodies; ++b) m.kinetic.push_back(static_cast<float>(share[2 * b]));
  }
  page.frames = frames;
  return m;
}

// The beams of a run as tubes: each one's node bodies in order (from the segments that the
// results file's XDMF views hold) and a radius that gives the tube its section's polar
// radius of gyration, as a solid round bar would (sqrt(2 I_axis / m) of a node), at least
// 0.4 % of the extent so that it is seen.
nlohmann::json beam_tubes(const ResultsFile& r, const Model& model, double scale) {
  nlohmann::json beams = nlohmann::json::array();
  if (!r.has("/xdmf/beam_lines") || !r.has("/xdmf/beam_index")) return beams;
  const std::vector<double> lines = r.read("/xdmf/beam_lines"), index = r.read("/xdmf/beam_index");
  if (lines.size() != 2 * index.size()) return beams;
  std::vector<int> nodes;
  const auto close = [&] {
    if (nodes.empty()) return;
    const Body& b = model.bodies.at(static_cast<std::size_t>(nodes[nodes.size() / 2]));
    const double axis = std::min({b.inertia[0], b.inertia[1], b.inertia[2]});
    const double radius = b.mass > 0 && axis > 0 ? std::sqrt(2 * axis / b.mass) : 0.0;
    beams.push_back({{"nodes", nodes}, {"radius", std::max(radius, 0.004 * scale)}});
    nodes.clear();
  };
  for (std::size_t e = 0; e < index.size(); ++e) {
    if (e > 0 && index[e] != index[e - 1]) close();
    const int from = static_cast<int>(lines[2 * e]), to = static_cast<int>(lines[2 * e + 1]);
    if (from < 0 || to < 0 || static_cast<std::size_t>(std::max(from, to)) >= model.bodies.size()) return nlohmann::json::array();
    if (nodes.empty()) nodes.push_back(from);
    nodes.push_back(to);
  }
  close();
  return beams;
}

// The flexible bodies' surfaces (FloatingFrameData::display_*) at each frame of a run, in
// the world: at the frame body's place, deformed by the modal coordinates. Left out where
// the part has no surface, the results no modal coordinates or orientations, or the points
// would pass the page's data budget.
struct Surface {
  const FlexibleBody* body = nullptr;
  std::vector<float> points;  // frames x points x 3
};

std::vector<Surface> flexible_surfaces(const ResultsFile& r, const Model& model, const Motion& m, const ViewerSettings& s) {
  std::vector<Surface> out;
  if (model.flexible.empty() || m.rows.empty() || !m.orientation || !r.has(modal_coordinates_dataset)) return out;
  double bytes = 0.0;
  for (const FlexibleBody& f : model.flexible) bytes += 12.0 * static_cast<double>(f.data->display_position.cols() * m.rows.size());
  if (bytes > s.max_megabytes * 1e6) return out;
  std::vector<std::vector<double>> eta;  // per frame, every flexible body's
  for (std::size_t k : m.rows) eta.push_back(r.read_row(modal_coordinates_dataset, k));
  std::size_t first = 0;
  for (const FlexibleBody& f : model.flexible) {
    const FloatingFrameData& d = *f.data;
    const Eigen::Index ne = d.modes(), points = d.display_position.cols();
    if (points > 0) {
      std::vector<float> at;
      at.reserve(static_cast<std::size_t>(3 * points) * m.rows.size());
      for (std::size_t k = 0; k < m.rows.size(); ++k) {
        const std::size_t body = k * m.bodies + static_cast<std::size_t>(f.frame);
        const float* q = &m.quaternion[4 * body];
        const Eigen::Matrix3d turn = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
        const Eigen::Vector3d origin(m.position[3 * body], m.position[3 * body + 1], m.position[3 * body + 2]);
        const Eigen::Matrix3Xf x =
            flexible_surface_points(d, origin, turn, Eigen::Map<const Eigen::VectorXd>(eta[k].data() + first, ne)).cast<float>();
        at.insert(at.end(), x.data(), x.data() + x.size());
      }
      out.push_back({&f, std::move(at)});
    }
    first += static_cast<std::size_t>(ne);
  }
  return out;
}

}  // namespace

ViewerPage viewer_page(const ResultsFile& r, const ViewerSettings& s) {
  if (r.ode()) throw InputError(r.path() + ": the results of mbsflow ode hold no bodies to show (mbsflow plot draws them)");
  ViewerPage page;
  const Motion motion = r.modes() ? mode_motion(r, s, page) : run_motion(r, s, page);
  const std::size_t n = motion.bodies, joints = motion.joints;
  const bool orientation = motion.orientation, ends = joints > 0;
  const std::vector<float>&position = motion.position, &attachment = motion.attachment;
  const Model model = read_model_text(r.model_text().value_or(""), r.path() + " (its model)");
  if (model.bodies.size() != n) throw InputError(r.path() + ": its model has another number of bodies than its results");

  const std::vector<Surface> surfaces = flexible_surfaces(r, model, motion, s);
  // The extent of the motion: every body, joint and surface point over the frames shown (a
  // single pendulum bob sweeps its circle; its pivot is a joint point).
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  std::vector<const std::vector<float>*> all_points{&position, &attachment};
  for (const Surface& surface : surfaces) all_points.push_back(&surface.points);
  for (const std::vector<float>* points : all_points)
    for (std::size_t k = 0; k + 2 < points->size(); k += 3) {
      const Eigen::Vector3f x((*points)[k], (*points)[k + 1], (*points)[k + 2]);
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  const double extent = static_cast<double>((hi - lo).maxCoeff());
  const double scale = extent > 0 && std::isfinite(extent) ? extent : 1.0;
  // Bodies without a usable inertia are drawn as spheres of 2 % of the extent, and every
  // body at least 1 % of it across (a point mass, a thin rod), so all are seen at any scale.
  std::vector<float> size;
  for (const Body& b : model.bodies)
    for (double a : ellipsoid(b, 0.02 * scale)) size.push_back(static_cast<float>(std::max(a, 0.01 * scale)));
  // A beam's nodes are beads on its tube, a little wider than it.
  const nlohmann::json beams = beam_tubes(r, model, scale);
  for (const nlohmann::json& beam : beams)
    for (int node : beam["nodes"]) std::fill_n(size.begin() + 3 * node, 3, static_cast<float>(1.3 * beam["radius"].get<double>()));
  // A flexible body drawn as its surface: its frame and node bodies are small beads on it
  // (their masses are the part's, not their shapes).
  nlohmann::json surface_data = nlohmann::json::array();
  for (const Surface& surface : surfaces) {
    const FlexibleBody& f = *surface.body;
    for (int b : f.nodes) std::fill_n(size.begin() + 3 * b, 3, static_cast<float>(0.01 * scale));
    std::fill_n(size.begin() + 3 * f.frame, 3, static_cast<float>(0.01 * scale));
    surface_data.push_back({{"name", f.name}, {"triangles", f.data->display_triangle}, {"points", base64(surface.points)}});
  }
  // The bodies of each joint's two ends (-1: ground), for the links drawn from a body's
  // centre to its joint points.
  std::vector<int> joint_bodies;
  if (ends && model.joints.size() == joints)
    for (const Joint& j : model.joints) joint_bodies.insert(joint_bodies.end(), {j.body1 == ground ? -1 : j.body1, j.body2});
  const Eigen::Vector3d g(model.gravity[0], model.gravity[1], model.gravity[2]);
  const Eigen::Vector3d up = g.norm() > 0 ? Eigen::Vector3d(-g.normalized()) : Eigen::Vector3d(0, 1, 0);

  nlohmann::json data;
  data["name"] = model.name;
  data["refresh"] = s.refresh_seconds;
  data["t"] = motion.times;
  data["bodies"] = n;
  data["joints"] = joints;
  data["position"] = base64(position);
  data["orientation"] = orientation ? nlohmann::json(base64(motion.quaternion)) : nlohmann::json();
  data["attachment"] = ends ? nlohmann::json(base64(attachment)) : nlohmann::json();
  data["size"] = base64(size);
  data["joint_bodies"] = joint_bodies;
  data["beams"] = beams;
  data["surfaces"] = surface_data;
  data["up"] = {up.x(), up.y(), up.z()};
  data["extent"] = scale;
  data["quantities"] = nlohmann::json::object();
  if (!motion.speed.empty()) data["quantities"]["speed [m/s]"] = base64(motion.speed);
  if (!motion.angular_speed.empty()) data["quantities"]["angular speed [rad/s]"] = base64(motion.angular_speed);
  if (!motion.kinetic.empty()) data["quantities"][r.modes() ? "kinetic share of the mode" : "kinetic energy [J]"] = base64(motion.kinetic);

  page.html = file_text(shared_file("viewer.html"));
  replace(page.html, "/*THREE*/", file_text(three_js_file("three.min.js")));
  replace(page.html, "/*ORBIT*/", file_text(three_js_file("examples/js/controls/OrbitControls.js")));
  replace(page.html, "/*DATA*/", data.dump());
  return page;
}

}  // namespace mbsflow::cli
