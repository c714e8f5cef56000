// The constraint rows of every kinematic joint against finite differences along a known
// motion: phi' = j.V + rate and phi'' = j.A + bias, so that the index-1 solve, the
// projection and the compliant joints all rest on correct derivatives.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <array>

#include "constraint_rows.hpp"

using namespace mbsflow;

namespace {

// A body moving with constant world angular velocity w and constant acceleration a.
struct Path {
  Eigen::Vector3d r0, v0, a, w;
  Eigen::Matrix3d R0;
  BodyMotion at(double t) const {
    BodyMotion m;
    m.r = r0 + v0 * t + 0.5 * a * t * t;
    m.v = v0 + a * t;
    m.R = Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix() * R0;
    m.w = w;
    return m;
  }
};

Path path(int seed) {
  Eigen::Vector3d v[4];
  for (int i = 0; i < 4; ++i)
    v[i] = Eigen::Vector3d(std::sin(1.3 * seed + i), std::cos(0.7 * seed + 2 * i), std::sin(0.4 * seed * i + 1));
  return {v[0], v[1], v[2], v[3], Eigen::Matrix3d(Eigen::AngleAxisd(0.3 * seed + 0.2, v[0].normalized()))};
}

}  // namespace

TEST_CASE("every joint's rows have the rates and accelerations of finite differences", "[joints]") {
  const JointType types[] = {JointType::spherical, JointType::revolute,  JointType::prismatic, JointType::cylindrical,
                             JointType::universal, JointType::planar,    JointType::fixed,     JointType::distance,
                             JointType::screw};
  const JointMotor::Kind motors[] = {JointMotor::Kind::none, JointMotor::Kind::position, JointMotor::Kind::velocity};
  for (JointType type : types)
    for (JointMotor::Kind motor : motors) {
      const bool axis = type == JointType::revolute || type == JointType::prismatic;
      if (motor != JointMotor::Kind::none && !axis) continue;
      JointGeometry g;
      g.type = type;
      g.pa = {0.3, -0.2, 0.5};
      g.pb = {-0.4, 0.1, 0.2};
      g.fa = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
      g.fb = Eigen::AngleAxisd(-0.4, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
      g.length = 1.3;
      g.motor.kind = motor;
      g.motor.function = TimeFunction::harmonic(0.5, 0.8, 0.3);
      const Path pa = path(1), pb = path(2);
      const int n = constraint_rows(g);
      CAPTURE(joint_type_name(type), static_cast<int>(motor), n);
      const double t = 0.37, d = 1e-4;
      std::array<ConstraintRow, 7> r0, rp, rm;
      evaluate_constraint(g, pa.at(t), pb.at(t), t, r0.data());
      evaluate_constraint(g, pa.at(t + d), pb.at(t + d), t + d, rp.data());
      evaluate_constraint(g, pa.at(t - d), pb.at(t - d), t - d, rm.data());
      Eigen::Matrix<double, 12, 1> V, A;
      V << pa.at(t).v, pa.w, pb.at(t).v, pb.w;
      A << pa.a, Eigen::Vector3d::Zero(), pb.a, Eigen::Vector3d::Zero();
      for (int k = 0; k < n; ++k) {
        CAPTURE(k);
        // The angle row's rate is z_a . (w_b - w_a), exact only where x_b is perpendicular
        // to z_a, i.e. on the revolute joint; the motor tests check it in motion there, and
        // the falling nut the screw's coupling, which holds the angle too.
        const bool angle_row = (type == JointType::revolute && motor != JointMotor::Kind::none) || type == JointType::screw;
        if (angle_row && k == n - 1) continue;
        const auto& r = r0[static_cast<std::size_t>(k)];
        const double rate = r.j.dot(V) + r.rate;
        const double accel = r.j.dot(A) + r.bias;
        if (r.holonomic) {
          CHECK(rate == Approx((rp[static_cast<std::size_t>(k)].phi - rm[static_cast<std::size_t>(k)].phi) / (2 * d)).margin(1e-6));
        }
        // The second derivative from the rates of the neighbouring times.
        auto rate_at = [&](const std::array<ConstraintRow, 7>& rows, double s) {
          Eigen::Matrix<double, 12, 1> v;
          v << pa.at(s).v, pa.w, pb.at(s).v, pb.w;
          return rows[static_cast<std::size_t>(k)].j.dot(v) + rows[static_cast<std::size_t>(k)].rate;
        };
        CHECK(accel == Approx((rate_at(rp, t + d) - rate_at(rm, t - d)) / (2 * d)).margin(1e-6));
      }
    }
}

TEST_CASE("a joint at rest in its frames violates nothing", "[joints]") {
  for (JointType type : {JointType::revolute, JointType::prismatic, JointType::fixed, JointType::planar, JointType::cylindrical,
                        JointType::screw}) {
    JointGeometry g;
    g.type = type;
    g.length = 0.05;  // the screw's pitch
    g.pa = {0.5, 0, 0};
    g.pb = {-0.5, 0, 0};
    BodyMotion a, b;
    a.r = {0, 0, 0};
    b.r = {1, 0, 0};
    std::array<ConstraintRow, 7> rows;
    evaluate_constraint(g, a, b, 0.0, rows.data());
    for (int k = 0; k < constraint_rows(g); ++k) CHECK(rows[static_cast<std::size_t>(k)].phi == Approx(0.0).margin(1e-15));
  }
}
