#include "mbsflow/graph/beams.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "mbsflow/error.hpp"
#include "as_eigen.hpp"

namespace mbsflow {
namespace {

Vec3 arr(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Quat quat(const Eigen::Matrix3d& r) {
  Eigen::Quaterniond q(r);
  q.normalize();
  return {q.w(), q.x(), q.y(), q.z()};
}

void require_positive(double v, const std::string& beam, const char* field) {
  if (!(v > 0.0) || !std::isfinite(v)) throw InputError("beam '" + beam + "': " + field + " must be a positive number");
}

// The frame with x along `axis` and y the part of `up` perpendicular to it.
Eigen::Matrix3d section_frame(const Eigen::Vector3d& axis, const Eigen::Vector3d& up, const std::string& beam, std::size_t node) {
  const Eigen::Vector3d x = axis.normalized();
  const Eigen::Vector3d y_raw = up - up.dot(x) * x;
  if (y_raw.norm() < 1e-6 * up.norm() || up.norm() == 0.0)
    throw InputError("beam '" + beam + "': up is parallel to the beam's axis at node " + std::to_string(node) +
                     " (give an up across the beam)");
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y_raw.normalized();
  r.col(2) = x.cross(r.col(1));
  return r;
}

}  // namespace

std::vector<Vec3> straight_beam_points(const Vec3& from, const Vec3& to, int elements) {
  if (elements < 1) throw InputError("a beam needs at least one element");
  std::vector<Vec3> out;
  const Eigen::Vector3d a = vec(from), b = vec(to);
  for (int i = 0; i <= elements; ++i) out.push_back(arr(a + (b - a) * (static_cast<double>(i) / elements)));
  return out;
}

BeamParts make_beam(const BeamSpec& s, int first_body) {
  const std::string& name = s.name;
  require_positive(s.E, name, "E");
  require_positive(s.G, name, "G");
  require_positive(s.density, name, "density");
  require_positive(s.section.area, name, "section.area");
  require_positive(s.section.Iy, name, "section.Iy");
  require_positive(s.section.Iz, name, "section.Iz");
  require_positive(s.section.J, name, "section.J");
  if (!(s.stiffness_damping >= 0.0) || !std::isfinite(s.stiffness_damping) || !(s.mass_damping >= 0.0) ||
      !std::isfinite(s.mass_damping))
    throw InputError("beam '" + name + "': damping must be a number >= 0");
  const std::size_t n = s.points.size();
  if (n < 2) throw InputError("beam '" + name + "': needs at least 2 points (one element)");
  std::vector<double> length(n - 1);
  for (std::size_t e = 0; e + 1 < n; ++e) {
    length[e] = (vec(s.points[e + 1]) - vec(s.points[e])).norm();
    if (!(length[e] > 0.0)) throw InputError("beam '" + name + "': points " + std::to_string(e) + " and " + std::to_string(e + 1) + " coincide");
  }
  const Eigen::Vector3d up = vec(s.up);
  // Node frames: x along the centreline (the mean of the two elements' directions inside).
  std::vector<Eigen::Matrix3d> frame(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    if (i > 0) t += (vec(s.points[i]) - vec(s.points[i - 1])) / length[i - 1];
    if (i + 1 < n) t += (vec(s.points[i + 1]) - vec(s.points[i])) / length[i];
    if (t.norm() < 1e-9) throw InputError("beam '" + name + "': the beam turns back on itself at node " + std::to_string(i));
    frame[i] = section_frame(t, up, name, i);
  }
  const double rho = s.density, a = s.section.area;
  BeamParts out;
  for (std::size_t i = 0; i < n; ++i) {
    // Half of each element beside the node, as a rod of the section along the node's x.
    const double piece = 0.5 * ((i > 0 ? length[i - 1] : 0.0) + (i + 1 < n ? length[i] : 0.0));
    const double m = rho * a * piece;
    Body b;
    b.name = name + "." + std::to_string(i);
    b.mass = m;
    b.inertia = Vec6{rho * (s.section.Iy + s.section.Iz) * piece, rho * s.section.Iy * piece + m * piece * piece / 12.0,
                     rho * s.section.Iz * piece + m * piece * piece / 12.0, 0.0, 0.0, 0.0};
    b.position = s.points[i];
    b.orientation = quat(frame[i]);
    if (s.mass_damping > 0.0) {
      Load damping;
      damping.body = first_body + static_cast<int>(i);
      damping.damping = {s.mass_damping * m, s.mass_damping * m, s.mass_damping * m};
      for (std::size_t k = 0; k < 6; ++k) damping.angular_damping[k] = s.mass_damping * b.inertia.get()[k];
      out.loads.push_back(damping);
    }
    out.nodes.push_back(std::move(b));
  }
  for (std::size_t e = 0; e + 1 < n; ++e) {
    const double l = length[e];
    const Eigen::Vector3d pa = vec(s.points[e]), pb = vec(s.points[e + 1]), mid = 0.5 * (pa + pb);
    // The element's frame: x along its chord, y the mean of its nodes' y made perpendicular.
    const Eigen::Matrix3d fe = section_frame(pb - pa, frame[e].col(1) + frame[e + 1].col(1), name, e);
    double phi_y = 0.0, phi_z = 0.0;
    if (s.shear) {
      const double ay = s.section.shear_area_y > 0.0 ? s.section.shear_area_y : 5.0 / 6.0 * a;
      const double az = s.section.shear_area_z > 0.0 ? s.section.shear_area_z : 5.0 / 6.0 * a;
      phi_y = 12.0 * s.E * s.section.Iz / (s.G * ay * l * l);
      phi_z = 12.0 * s.E * s.section.Iy / (s.G * az * l * l);
    }
    const double l3 = l * l * l;
    const Vec6 k{s.E * a / l,
                 12.0 * s.E * s.section.Iz / (l3 * (1.0 + phi_y)),
                 12.0 * s.E * s.section.Iy / (l3 * (1.0 + phi_z)),
                 s.G * s.section.J / l,
                 s.E * s.section.Iy / l,
                 s.E * s.section.Iz / l};
    Vec6 c{};
    for (std::size_t i = 0; i < 6; ++i) c[i] = s.stiffness_damping * k[i];
    Joint j;
    j.name = name + ".e" + std::to_string(e);
    j.type = JointType::bushing;
    j.body1 = first_body + static_cast<int>(e);
    j.body2 = j.body1 + 1;
    j.point1 = arr(frame[e].transpose() * (mid - pa));
    j.point2 = arr(frame[e + 1].transpose() * (mid - pb));
    j.frame1 = quat(frame[e].transpose() * fe);
    j.frame2 = quat(frame[e + 1].transpose() * fe);
    j.stiffness = k;
    j.damping = c;
    out.elements.push_back(std::move(j));
  }
  return out;
}

void add_beam(Model& model, const BeamSpec& spec) {
  BeamParts parts = make_beam(spec, static_cast<int>(model.bodies.size()));
  BeamRecord r{spec.name, static_cast<int>(model.bodies.size()), static_cast<int>(parts.nodes.size()),
               static_cast<int>(model.joints.size()), static_cast<int>(parts.elements.size())};
  for (Body& b : parts.nodes) model.bodies.push_back(std::move(b));
  for (Joint& j : parts.elements) model.joints.push_back(std::move(j));
  model.loads.insert(model.loads.end(), parts.loads.begin(), parts.loads.end());
  model.beams.push_back(std::move(r));
}

}  // namespace mbsflow
