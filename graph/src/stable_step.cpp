#include "mbsflow/graph/stable_step.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace mbsflow {
namespace {

struct Disc {
  double stiffness = 0.0;  // sum of mass-scaled stiffness (Gershgorin row sum)
  double damping = 0.0;
  double strongest = 0.0;
  int joint = -1;
};


// Translational and largest rotational stiffness (damping) of a joint, tables included.
struct JointRates {
  double kt = 0.0, kr = 0.0, ct = 0.0, cr = 0.0;
};

JointRates rates(const Joint& j) {
  JointRates r;
  if (j.type == JointType::spring) {
    r.kt = j.stiffness[0];
    r.ct = j.damping[0];
    return r;
  }
  for (std::size_t a = 0; a < 6; ++a) {
    const double k = j.tables[a].empty() ? j.stiffness[a] : table_max_slope(j.tables[a]);
    (a < 3 ? r.kt : r.kr) = std::max(a < 3 ? r.kt : r.kr, k);
    (a < 3 ? r.ct : r.cr) = std::max(a < 3 ? r.ct : r.cr, j.damping[a]);
  }
  return r;
}

}  // namespace

StableStep estimate_stable_step(const Model& model) {
  const std::size_t n = model.bodies.size();
  std::vector<bool> driven(n, false);
  for (const Driver& d : model.drivers) driven[static_cast<std::size_t>(d.body)] = true;
  // One translational disc per body and one rotational disc per body axis.
  std::vector<Disc> trans(n);
  std::vector<std::array<Disc, 3>> rot(n);
  auto inertia = [&](int b, std::size_t axis) { return model.bodies[static_cast<std::size_t>(b)].inertia[axis]; };
  auto add = [](Disc& d, double k, double c, double self, double other, int joint) {
    // Row of M^-1/2 K M^-1/2: k/self on the diagonal, k/sqrt(self*other) off it.
    const double scale = 1.0 / self + (other > 0.0 ? 1.0 / std::sqrt(self * other) : 0.0);
    d.stiffness += k * scale;
    d.damping += c * scale;
    if (k * scale > d.strongest) {
      d.strongest = k * scale;
      d.joint = joint;
    }
  };
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& j = model.joints[k];
    const JointRates r = rates(j);
    const int ends[2] = {j.body1, j.body2};
    const Vec3* points[2] = {&j.point1.get(), &j.point2.get()};
    for (int s = 0; s < 2; ++s) {
      const int b = ends[s], o = ends[1 - s];
      if (b == ground || driven[static_cast<std::size_t>(b)]) continue;
      const bool other_fixed = o == ground || driven[static_cast<std::size_t>(o)];
      const Body& body = model.bodies[static_cast<std::size_t>(b)];
      const double om = other_fixed ? 0.0 : model.bodies[static_cast<std::size_t>(o)].mass;
      add(trans[static_cast<std::size_t>(b)], r.kt, r.ct, body.mass, om, static_cast<int>(k));
      // A translational spring at lever arm l resists rotation about an axis with k l_perp^2.
      const Vec3& p = *points[s];
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double lever2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - p[axis] * p[axis];
        const double oi = other_fixed ? 0.0 : inertia(o, axis);
        add(rot[static_cast<std::size_t>(b)][axis], r.kr + r.kt * lever2, r.cr + r.ct * lever2, inertia(b, axis), oi,
            static_cast<int>(k));
      }
    }
  }
  StableStep out;
  for (std::size_t b = 0; b < n; ++b) {
    for (const Disc* d : {&trans[b], &rot[b][0], &rot[b][1], &rot[b][2]}) {
      // Largest |root| of lambda^2 - c lambda - k, a bound for lambda^2 + c lambda + k = 0.
      const double lambda = 0.5 * d->damping + std::sqrt(0.25 * d->damping * d->damping + d->stiffness);
      if (lambda > out.lambda_max) {
        out.lambda_max = lambda;
        out.body = static_cast<int>(b);
        out.joint = d->joint;
      }
    }
  }
  out.step = out.lambda_max > 0.0 ? rk4_stability_radius / out.lambda_max : std::numeric_limits<double>::infinity();
  return out;
}

std::vector<double> joint_rates(const Model& model) {
  std::vector<bool> driven(model.bodies.size(), false);
  for (const Driver& d : model.drivers) driven[static_cast<std::size_t>(d.body)] = true;
  auto held = [&](int b) { return b == ground || driven[static_cast<std::size_t>(b)]; };
  std::vector<double> out;
  out.reserve(model.joints.size());
  for (const Joint& j : model.joints) {
    if (is_kinematic(j.type) && j.rigid) {
      out.push_back(std::numeric_limits<double>::infinity());
      continue;
    }
    const JointRates r = rates(j);
    const int ends[2] = {j.body1, j.body2};
    const Vec3* points[2] = {&j.point1.get(), &j.point2.get()};
    double trans = 0.0, rot[3] = {0.0, 0.0, 0.0};
    for (int s = 0; s < 2; ++s) {
      if (held(ends[s])) continue;
      const Body& b = model.bodies[static_cast<std::size_t>(ends[s])];
      trans += r.kt / b.mass;
      const Vec3& p = *points[s];
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double lever2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - p[axis] * p[axis];
        rot[axis] += (r.kr + r.kt * lever2) / b.inertia[axis];
      }
    }
    out.push_back(std::sqrt(std::max({trans, rot[0], rot[1], rot[2]})));
  }
  return out;
}

std::string StableStep::describe(const Model& model) const {
  char buf[256];
  if (joint < 0) return "no joint limits the step";
  std::snprintf(buf, sizeof buf, "%.3g s (from joint '%s' at body '%s', fastest eigenvalue bound %.4g 1/s)", step,
                model.joints[static_cast<std::size_t>(joint)].name.c_str(),
                model.bodies[static_cast<std::size_t>(body)].name.c_str(), lambda_max);
  return buf;
}

}  // namespace mbsflow
