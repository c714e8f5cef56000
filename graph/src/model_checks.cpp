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

// Where a checked value sits ("joint 3 'j3' limits stiffness"), put into words only when a
// check fails: a million joints' checks would otherwise build some twenty million strings.
struct Place {
  const char* item = "";  // "body", "joint", ... or the whole place ("gravity")
  std::size_t index = npos;
  const std::string* name = nullptr;
  std::array<const char*, 2> fields{};  // nested: "limits", "stiffness"
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

  Place operator/(const char* field) const {
    Place p = *this;
    (p.fields[0] ? p.fields[1] : p.fields[0]) = field;
    return p;
  }
  std::string text() const {
    std::string s = item;
    if (index != npos) s += " " + std::to_string(index);
    if (name) s += " '" + *name + "'";
    for (const char* f : fields)
      if (f) s += std::string(" ") + f;
    return s;
  }
};

[[noreturn]] void bad(const Place& where, const std::string& what) { throw InputError(where.text() + ": " + what); }

template <std::size_t N>
void finite(const std::array<double, N>& v, const Place& where) {
  for (double x : v)
    if (!std::isfinite(x)) bad(where, "must be finite (got " + text(x) + ")");
}
void finite(double x, const Place& where) { finite(std::array<double, 1>{x}, where); }

template <std::size_t N>
void non_negative(const std::array<double, N>& v, const Place& where) {
  finite(v, where);
  for (double x : v)
    if (x < 0.0) bad(where, "must be >= 0 (got " + text(x) + ")");
}

void positive(double x, const Place& where) {
  if (!(std::isfinite(x) && x > 0.0)) bad(where, "must be a finite number > 0 (got " + text(x) + ")");
}

void rotation(const Quat& q, const Place& where) {
  finite(q, where);
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 1e-12)) bad(where, "must be a rotation quaternion (norm " + text(norm) + ")");
}

void increasing(const std::vector<double>& x, const std::vector<double>& y, const Place& where) {
  if (x.size() != y.size()) bad(where, "needs as many values as points (" + std::to_string(x.size()) + ", " + std::to_string(y.size()) + ")");
  for (std::size_t i = 0; i < x.size(); ++i) {
    finite(x[i], where);
    finite(y[i], where);
    if (i > 0 && !(x[i] > x[i - 1])) bad(where, "points must be strictly increasing");
  }
}

void check_function(const TimeFunction& f, const Place& where) {
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
      positive(f.cutoff, where / "cutoff");
      break;
    default:
      break;
  }
}

void check_body(const Body& b, const Place& where) {
  positive(b.mass, where / "mass");
  finite(b.inertia.get(), where / "inertia");
  const Vec6& i = b.inertia;
  Eigen::Matrix3d m;
  m << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(e[0] > 0.0)) bad(where / "inertia", "must be positive definite (smallest principal moment " + text(e[0]) + ")");
  finite(b.position, where / "position");
  rotation(b.orientation, where / "orientation");
  finite(b.velocity, where / "velocity");
  finite(b.angular_velocity, where / "angular_velocity");
}

void check_joint(const Joint& j, int bodies, const Place& where) {
  if (j.body1 < ground || j.body1 >= bodies) bad(where / "body1", "no body " + std::to_string(j.body1));
  if (j.body2 < 0 || j.body2 >= bodies) bad(where / "body2", "no body " + std::to_string(j.body2));
  if (j.body1 == j.body2) bad(where, "joins body " + std::to_string(j.body2) + " to itself");
  finite(j.point1.get(), where / "point1");
  finite(j.point2.get(), where / "point2");
  rotation(j.frame1, where / "frame1");
  rotation(j.frame2, where / "frame2");
  non_negative(j.stiffness.get(), where / "stiffness");
  non_negative(j.damping.get(), where / "damping");
  finite(j.preload.get(), where / "preload");
  non_negative(std::array<double, 1>{j.rest_length}, where / "rest_length");
  for (const ForceTable& t : j.tables)
    if (!t.empty()) {
      if (t.deflection.size() < 2) bad(where / "tables", "a table needs at least 2 points");
      increasing(t.deflection, t.force, where / "tables");
    }
  check_function(j.motor->function, where / "motor");
  if (j.limits->active) {
    finite(std::array<double, 2>{j.limits->lower, j.limits->upper}, where / "limits");
    if (!(j.limits->upper > j.limits->lower)) bad(where / "limits", "upper must be > lower");
    positive(j.limits->stiffness, where / "limits" / "stiffness");
    non_negative(std::array<double, 1>{j.limits->damping}, where / "limits" / "damping");
  }
}

void check_body_index(int body, int bodies, const Place& where) {
  if (body < 0 || body >= bodies) bad(where, "no body " + std::to_string(body) + " (the model has " + std::to_string(bodies) + ")");
}

void check_settings(const SimulationSettings& s) {
  finite(std::array<double, 2>{s.t_start, s.t_end}, {"simulation t_start, t_end"});
  if (!(s.t_end > s.t_start)) bad({"simulation"}, "t_end must be > t_start (" + text(s.t_start) + ", got " + text(s.t_end) + ")");
  if (s.step) positive(*s.step, {"simulation step"});
  if (s.output_interval) positive(*s.output_interval, {"simulation output_interval"});
  if (s.output_every && *s.output_every < 1)
    bad({"simulation output_every"}, "must be >= 1 (got " + std::to_string(*s.output_every) + ")");
  positive(s.rtol, {"simulation rtol"});
  positive(s.atol, {"simulation atol"});
}

}  // namespace

void check_model(const Model& m) {
  if (m.bodies.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 16))
    bad({"model"}, "too many bodies (" + std::to_string(m.bodies.size()) + ")");
  const int n = static_cast<int>(m.bodies.size());
  finite(m.gravity, {"gravity"});
  for (std::size_t b = 0; b < m.bodies.size(); ++b) check_body(m.bodies[b], {"body", b, &m.bodies[b].name});
  for (std::size_t k = 0; k < m.joints.size(); ++k) check_joint(m.joints[k], n, {"joint", k, &m.joints[k].name});
  for (std::size_t k = 0; k < m.loads.size(); ++k) {
    const Load& l = m.loads[k];
    const Place where{"load", k};
    check_body_index(l.body, n, where / "body");
    finite(l.force, where / "force");
    finite(l.torque, where / "torque");
    finite(l.point, where / "point");
    finite(l.damping, where / "damping");
    finite(l.angular_damping, where / "angular_damping");
    check_function(l.function, where / "function");
  }
  for (std::size_t k = 0; k < m.drivers.size(); ++k) {
    const Driver& d = m.drivers[k];
    const Place where{"driver", k};
    check_body_index(d.body, n, where / "body");
    finite(d.velocity, where / "velocity");
    for (const TimeFunction& f : d.displacement) check_function(f, where / "displacement");
  }
  for (std::size_t k = 0; k < m.force_elements.size(); ++k)
    if (!m.force_elements[k]) bad({"force element", k}, "is null");
  check_settings(m.simulation);
}

}  // namespace mbsflow
