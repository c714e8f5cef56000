#include "arc_step.hpp"

#include <Eigen/Geometry>
#include <algorithm>

namespace mbsflow {
namespace {

// Where the point p of a body at orientation r goes when the body turns by phi, less where
// the linear step put it (r p + phi x r p): the rotation's remainder, second order in phi.
Eigen::Vector3d turn_remainder(const Eigen::Vector3d& phi, const Eigen::Quaterniond& r, const Eigen::Vector3d& p) {
  const double angle = phi.norm();
  if (angle == 0.0) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d arm = r * p;
  return Eigen::AngleAxisd(angle, phi / angle) * arm - arm - phi.cross(arm);
}

}  // namespace

ArcStep::ArcStep(const Model& model, const FreeCoordinates& coords) : coords_(coords) {
  const std::vector<int> free_of = coords.free_index(model.bodies.size());
  const auto side = [&](int body) { return body < 0 ? -1 : free_of[static_cast<std::size_t>(body)]; };
  for (const Joint& j : model.joints) {
    const Vec6& k = j.stiffness;
    double weight = 0.0;
    if (j.type == JointType::bushing)
      weight = (k[0] + k[1] + k[2]) / 3.0;
    else if (!j.rigid && (j.type == JointType::revolute || j.type == JointType::spherical ||
                          j.type == JointType::universal || j.type == JointType::fixed))
      weight = std::max({k[0], k[1], k[2]});  // a compliant joint holding a point
    const int a = side(j.body1), b = side(j.body2);
    if (weight <= 0.0 || (a < 0 && b < 0)) continue;
    const Vec3 &p1 = j.point1, &p2 = j.point2;
    connections_.push_back({a, b, weight, Eigen::Vector3d(p1[0], p1[1], p1[2]), Eigen::Vector3d(p2[0], p2[1], p2[2])});
  }
  if (connections_.empty()) return;
  double stiffest = 0.0;
  for (const Connection& c : connections_) stiffest = std::max(stiffest, c.weight);
  // A body with no connection, or a part that floats, keeps its mean where the step put
  // it: a weight far below the connections' on every body.
  const auto n = static_cast<Eigen::Index>(coords.bodies.size());
  std::vector<Eigen::Triplet<double>> terms;
  for (Eigen::Index k = 0; k < n; ++k) terms.emplace_back(k, k, 1e-9 * stiffest);
  for (const Connection& c : connections_) {
    if (c.a >= 0) terms.emplace_back(c.a, c.a, c.weight);
    if (c.b >= 0) terms.emplace_back(c.b, c.b, c.weight);
    if (c.a >= 0 && c.b >= 0) {
      terms.emplace_back(c.a, c.b, -c.weight);
      terms.emplace_back(c.b, c.a, -c.weight);
    }
  }
  Eigen::SparseMatrix<double> l(n, n);
  l.setFromTriplets(terms.begin(), terms.end());
  laplacian_.compute(l);
}

void ArcStep::apply(const StateLayout& l, const Eigen::VectorXd& dx, Eigen::VectorXd& y) const {
  if (connections_.empty() || laplacian_.info() != Eigen::Success) return apply_tangent_step(l, coords_, dx, y);
  const auto orientation = [&](int k) {
    const auto q = y.segment<4>(l.orientation(coords_.bodies[static_cast<std::size_t>(k)]));
    return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
  };
  const auto remainder = [&](int k, const Eigen::Vector3d& p) -> Eigen::Vector3d {
    if (k < 0) return Eigen::Vector3d::Zero();
    return turn_remainder(dx.segment<3>(coords_.start[static_cast<std::size_t>(k)] + 3), orientation(k), p);
  };
  // Minimises sum w |d_b - d_a + s_b - s_a|^2: the gap each connection's remainders s open.
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(coords_.bodies.size()), 3);
  for (const Connection& c : connections_) {
    const Eigen::Vector3d gap = remainder(c.b, c.pb) - remainder(c.a, c.pa);
    if (c.b >= 0) rhs.row(c.b) -= c.weight * gap.transpose();
    if (c.a >= 0) rhs.row(c.a) += c.weight * gap.transpose();
  }
  const Eigen::MatrixXd d = laplacian_.solve(rhs);
  Eigen::VectorXd moved = dx;
  for (std::size_t k = 0; k < coords_.bodies.size(); ++k) moved.segment<3>(coords_.start[k]) += d.row(static_cast<Eigen::Index>(k)).transpose();
  apply_tangent_step(l, coords_, moved, y);
}

}  // namespace mbsflow
