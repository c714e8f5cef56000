#include "viewer_page.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "mbsflow/error.hpp"
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

}  // namespace

ViewerPage viewer_page(const ResultsFile& r, const ViewerSettings& s) {
  if (r.ode()) throw InputError(r.path() + ": the results of mbsflow ode hold no bodies to show (mbsflow plot draws them)");
  if (!r.has("/bodies/position")) throw InputError(r.path() + ": no body positions to show (run with --fields position)");
  const std::vector<double> t = r.time();
  const std::size_t rows = std::min<std::size_t>(t.size(), r.shape("/bodies/position")[0]);
  if (rows == 0) throw InputError(r.path() + ": no snapshots yet");
  const std::size_t n = r.body_names().size();
  const bool orientation = r.has("/bodies/orientation"), velocity = r.has("/bodies/velocity");
  const bool spin = r.has("/bodies/angular_velocity"), ends = r.has(joint_attachment_dataset);
  const bool energies = r.has(body_energy_dataset);
  const std::size_t joints = ends ? r.shape(joint_attachment_dataset)[1] : 0;
  const Model model = read_model_text(r.model_text().value_or(""), r.path() + " (its model)");
  if (model.bodies.size() != n) throw InputError(r.path() + ": its model has another number of bodies than its results");

  // Frames: evenly spread over the snapshots, the last included, within the data budget.
  const double frame_bytes = 4.0 * (static_cast<double>(n) * (3 + 4 + 3) + 6.0 * static_cast<double>(joints));
  const auto budget = static_cast<std::size_t>(std::max(1.0, s.max_megabytes * 1e6 / frame_bytes));
  const std::size_t most = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(s.max_frames), budget));
  ViewerPage page;
  const std::vector<std::size_t> picked = evenly_spread_rows(rows, most);
  page.frames = static_cast<long>(picked.size());
  page.stride = picked.size() > 1 ? static_cast<long>(picked[1] - picked[0]) : 1;

  std::vector<float> position, quaternion, attachment, speed, angular_speed, kinetic;
  std::vector<double> times;
  auto append = [](std::vector<float>& to, const std::vector<double>& from) { to.insert(to.end(), from.begin(), from.end()); };
  for (std::size_t k : picked) {
    times.push_back(t[k]);
    append(position, r.read_row("/bodies/position", k));
    if (orientation) append(quaternion, r.read_row("/bodies/orientation", k));
    if (ends) append(attachment, r.read_row(joint_attachment_dataset, k));
    const std::vector<double> v = velocity ? r.read_row("/bodies/velocity", k) : std::vector<double>{};
    const std::vector<double> w = spin ? r.read_row("/bodies/angular_velocity", k) : std::vector<double>{};
    const std::vector<double> e = energies ? r.read_row(body_energy_dataset, k) : std::vector<double>{};
    for (std::size_t i = 0; i < n; ++i) {
      if (velocity) speed.push_back(static_cast<float>(Eigen::Vector3d(v[3 * i], v[3 * i + 1], v[3 * i + 2]).norm()));
      if (spin) angular_speed.push_back(static_cast<float>(Eigen::Vector3d(w[3 * i], w[3 * i + 1], w[3 * i + 2]).norm()));
      if (energies) kinetic.push_back(static_cast<float>(e[2 * i]));
    }
  }
  // The extent of the motion: every body and joint point over the frames shown (a single
  // pendulum bob sweeps its circle; its pivot is a joint point).
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
  for (const std::vector<float>* points : {&position, &attachment})
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
  data["t"] = times;
  data["bodies"] = n;
  data["joints"] = joints;
  data["position"] = base64(position);
  data["orientation"] = orientation ? nlohmann::json(base64(quaternion)) : nlohmann::json();
  data["attachment"] = ends ? nlohmann::json(base64(attachment)) : nlohmann::json();
  data["size"] = base64(size);
  data["joint_bodies"] = joint_bodies;
  data["up"] = {up.x(), up.y(), up.z()};
  data["extent"] = scale;
  data["quantities"] = nlohmann::json::object();
  if (!speed.empty()) data["quantities"]["speed [m/s]"] = base64(speed);
  if (!angular_speed.empty()) data["quantities"]["angular speed [rad/s]"] = base64(angular_speed);
  if (!kinetic.empty()) data["quantities"]["kinetic energy [J]"] = base64(kinetic);

  page.html = file_text(shared_file("viewer.html"));
  replace(page.html, "/*THREE*/", file_text(three_js_file("three.min.js")));
  replace(page.html, "/*ORBIT*/", file_text(three_js_file("examples/js/controls/OrbitControls.js")));
  replace(page.html, "/*DATA*/", data.dump());
  return page;
}

}  // namespace mbsflow::cli
