// The library's own check of a Model: an embedding program that fills a Model by hand
// gets an InputError naming the bad field, never a crash or a NaN run. The JSON reader
// checks the same things first, with file positions; this is the second line for
// models that never were a file.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <limits>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/model.hpp"

namespace mbsflow {
namespace {

std::string text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

[[noreturn]] void bad(const std::string& where, const std::string& what) { throw InputError(where + ": " + what); }

template <std::size_t N>
void finite(const std::array<double, N>& v, const std::string& where) {
  for (double x : v)
    if (!std::isfinite(x)) bad(where, "must be finite (got " + text(x) + ")");
}
void finite(double x, const std::string& where) { finite(std::array<double, 1>{x}, where); }

template <std::size_t N>
void non_negative(const std::array<double, N>& v, const std::string& where) {
  finite(v, where);
  for (double x : v)
    if (x < 0.0) bad(where, "must be >= 0 (got " + text(x) + ")");
}

void positive(double x, const std::string& where) {
  if (!(std::isfinite(x) && x > 0.0)) bad(where, "must be a finite number > 0 (got " + text(x) + ")");
}

void rotation(const Quat& q, const std::string& where) {
  finite(q, where);
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 1e-12)) bad(where, "must be a rotation quaternion (norm " + text(norm) + ")");
}

void increasing(const std::vector<double>& x, const std::vector<double>& y, const std::string& where) {
  if (x.size() != y.size()) bad(where, "needs as many values as points (" + std::to_string(x.size()) + ", " + std::to_string(y.size()) + ")");
  for (std::size_t i = 0; i < x.size(); ++i) {
    finite(x[i], where);
    finite(y[i], where);
    if (i > 0 && !(x[i] > x[i - 1])) bad(where, "points must be strictly increasing");
  }
}

void check_function(const TimeFunction& f, const std::string& where) {
  finite(std::array<double, 7>{f.value, f.amplitude, f.frequency, f.phase, f.offset, f.cutoff, f.delay}, where);
  switch (f.kind) {
    case TimeFunction::Kind::table:
      if (f.times.empty()) bad(where, "a table needs at least one point");
      increasing(f.times, f.values, where);
      break;
    case TimeFunction::Kind::random:
      if (f.components < 1 || f.components > TimeFunction::max_components)
        bad(where, "components must be 1 to " + std::to_string(TimeFunction::max_components) + " (got " +
                       std::to_string(f.components) + ")");
      positive(f.cutoff, where + " cutoff");
      break;
    default:
      break;
  }
}

void check_body(const Body& b, const std::string& where) {
  positive(b.mass, where + " mass");
  finite(b.inertia, where + " inertia");
  const Vec6& i = b.inertia;
  Eigen::Matrix3d m;
  m << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(e[0] > 0.0)) bad(where + " inertia", "must be positive definite (smallest principal moment " + text(e[0]) + ")");
  finite(b.position, where + " position");
  rotation(b.orientation, where + " orientation");
  finite(b.velocity, where + " velocity");
  finite(b.angular_velocity, where + " angular_velocity");
}

void check_joint(const Joint& j, int bodies, const std::string& where) {
  if (j.body1 < ground || j.body1 >= bodies) bad(where + " body1", "no body " + std::to_string(j.body1));
  if (j.body2 < 0 || j.body2 >= bodies) bad(where + " body2", "no body " + std::to_string(j.body2));
  if (j.body1 == j.body2) bad(where, "joins body " + std::to_string(j.body2) + " to itself");
  finite(j.point1, where + " point1");
  finite(j.point2, where + " point2");
  rotation(j.frame1, where + " frame1");
  rotation(j.frame2, where + " frame2");
  non_negative(j.stiffness, where + " stiffness");
  non_negative(j.damping, where + " damping");
  finite(j.preload.get(), where + " preload");
  non_negative(std::array<double, 1>{j.rest_length}, where + " rest_length");
  for (const ForceTable& t : j.tables)
    if (!t.empty()) {
      if (t.deflection.size() < 2) bad(where + " tables", "a table needs at least 2 points");
      increasing(t.deflection, t.force, where + " tables");
    }
  check_function(j.motor->function, where + " motor");
  if (j.limits->active) {
    finite(std::array<double, 2>{j.limits->lower, j.limits->upper}, where + " limits");
    if (!(j.limits->upper > j.limits->lower)) bad(where + " limits", "upper must be > lower");
    positive(j.limits->stiffness, where + " limits stiffness");
    non_negative(std::array<double, 1>{j.limits->damping}, where + " limits damping");
  }
}

void check_body_index(int body, int bodies, const std::string& where) {
  if (body < 0 || body >= bodies) bad(where, "no body " + std::to_string(body) + " (the model has " + std::to_string(bodies) + ")");
}

void check_settings(const SimulationSettings& s) {
  finite(std::array<double, 2>{s.t_start, s.t_end}, "simulation t_start, t_end");
  if (!(s.t_end > s.t_start)) bad("simulation", "t_end must be > t_start (" + text(s.t_start) + ", got " + text(s.t_end) + ")");
  if (s.step) positive(*s.step, "simulation step");
  if (s.output_interval) positive(*s.output_interval, "simulation output_interval");
  if (s.output_every < 1) bad("simulation output_every", "must be >= 1 (got " + std::to_string(s.output_every) + ")");
  positive(s.rtol, "simulation rtol");
  positive(s.atol, "simulation atol");
}

}  // namespace

void check_model(const Model& m) {
  if (m.bodies.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 16))
    bad("model", "too many bodies (" + std::to_string(m.bodies.size()) + ")");
  const int n = static_cast<int>(m.bodies.size());
  finite(m.gravity, "gravity");
  for (int b = 0; b < n; ++b) check_body(m.bodies[static_cast<std::size_t>(b)], "body " + std::to_string(b) + " '" + m.bodies[static_cast<std::size_t>(b)].name + "'");
  for (std::size_t k = 0; k < m.joints.size(); ++k)
    check_joint(m.joints[k], n, "joint " + std::to_string(k) + " '" + m.joints[k].name + "'");
  for (std::size_t k = 0; k < m.loads.size(); ++k) {
    const Load& l = m.loads[k];
    const std::string where = "load " + std::to_string(k);
    check_body_index(l.body, n, where + " body");
    finite(l.force, where + " force");
    finite(l.torque, where + " torque");
    finite(l.point, where + " point");
    check_function(l.function, where + " function");
  }
  for (std::size_t k = 0; k < m.drivers.size(); ++k) {
    const Driver& d = m.drivers[k];
    const std::string where = "driver " + std::to_string(k);
    check_body_index(d.body, n, where + " body");
    finite(d.velocity, where + " velocity");
    for (const TimeFunction& f : d.displacement) check_function(f, where + " displacement");
  }
  for (std::size_t k = 0; k < m.force_elements.size(); ++k)
    if (!m.force_elements[k]) bad("force element " + std::to_string(k), "is null");
  check_settings(m.simulation);
}

}  // namespace mbsflow
