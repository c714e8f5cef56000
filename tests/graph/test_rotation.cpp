#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "rotation.hpp"

using namespace mbsflow;

namespace {
Eigen::Vector4d quat_from_vector(const Eigen::Vector3d& v) {
  const double a = v.norm();
  if (a == 0.0) return {1, 0, 0, 0};
  const Eigen::Vector3d u = v / a;
  return {std::cos(a / 2), std::sin(a / 2) * u[0], std::sin(a / 2) * u[1], std::sin(a / 2) * u[2]};
}
}  // namespace

TEST_CASE("rotation matrix matches Eigen and ignores the quaternion's norm", "[graph]") {
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.2).normalized();
  const Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
  CHECK((rotation_matrix(v) - q.toRotationMatrix()).norm() < 1e-15);
  CHECK((rotation_matrix(3.0 * v) - q.toRotationMatrix()).norm() < 1e-15);
  const Eigen::Quaterniond p = Eigen::Quaterniond(-0.1, 0.4, 0.2, 0.9).normalized();
  const Eigen::Vector4d pv(p.w(), p.x(), p.y(), p.z());
  const Eigen::Quaterniond qp = q * p;
  CHECK((quat_multiply(v, pv) - Eigen::Vector4d(qp.w(), qp.x(), qp.y(), qp.z())).norm() < 1e-15);
}

TEST_CASE("rotation vector inverts the exponential map up to pi", "[graph]") {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  for (double angle : {0.0, 1e-9, 1e-4, 0.3, 1.5, 3.0, 3.14}) {
    const Eigen::Vector3d v = angle * axis;
    CHECK((rotation_vector(quat_from_vector(v)) - v).norm() < 1e-12);
    CHECK((rotation_vector(-2.0 * quat_from_vector(v)) - v).norm() < 1e-12);  // sign and scale
  }
}

TEST_CASE("bushing torque is the exact gradient of the rotational energy", "[graph]") {
  // Energy V(theta) = 1/2 theta^T K theta of R = exp(theta). Perturbing R on the left by
  // exp(eps e_i) changes V at the rate g_i, the gradient that the bushing turns into torques.
  const Eigen::Vector3d k(1.0, 3.0, 7.0);
  auto energy = [&](const Eigen::Vector4d& q) {
    const Eigen::Vector3d th = rotation_vector(q);
    return 0.5 * th.dot(k.cwiseProduct(th));
  };
  for (double angle : {1e-9, 0.01, 0.09, 0.11, 0.8, 2.0, 2.9}) {
    const Eigen::Vector3d theta = angle * Eigen::Vector3d(0.3, -0.8, 0.5).normalized();
    const Eigen::Vector4d q = quat_from_vector(theta);
    const Eigen::Vector3d g = rotation_gradient_to_torque(rotation_log(q), k.cwiseProduct(theta));
    for (int i = 0; i < 3; ++i) {
      const double eps = 1e-6;
      const Eigen::Vector3d e = eps * Eigen::Vector3d::Unit(i);
      const double dv = (energy(quat_multiply(quat_from_vector(e), q)) - energy(quat_multiply(quat_from_vector(-e), q))) / (2 * eps);
      CHECK(g[i] == Approx(dv).epsilon(1e-6).margin(1e-9));
    }
  }
}

TEST_CASE("small-angle atan2 by its series: within 3 ulp of libm over its whole range", "[graph]") {
  std::mt19937_64 random(3);  // 200 000 draws: 1.0 ulp worst by Horner, 2.0 by Estrin
  std::uniform_real_distribution<double> ratio(0.0, 0.25), scale(-3.0, 3.0);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double w = std::pow(10.0, scale(random)), s = ratio(random) * w;
    const double exact = std::atan2(s, w);
    if (exact == 0.0) continue;
    worst = std::max(worst, std::abs(small_atan2(s, w) - exact) / (std::numeric_limits<double>::epsilon() * exact));
  }
  INFO("worst error " << worst << " ulp (of the value)");
  CHECK(worst <= 3.0);
  // At the switch to libm (s = w / 4) and at tiny angles.
  CHECK(std::abs(small_atan2(0.25, 1.0) - std::atan2(0.25, 1.0)) <= 3 * std::numeric_limits<double>::epsilon() * 0.245);
  CHECK(small_atan2(1e-300, 1.0) == std::atan2(1e-300, 1.0));
  CHECK(small_atan2(0.0, 1.0) == 0.0);
  // The rotation vector is continuous across the switch.
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 1.0, -0.4).normalized();
  const double half = std::atan(0.25);  // s / w = tan(angle / 2) = 1/4
  for (const double angle : {2 * half * (1 - 1e-12), 2 * half, 2 * half * (1 + 1e-12)}) {
    const Eigen::Vector3d v = angle * axis;
    CHECK((rotation_vector(quat_from_vector(v)) - v).norm() <= 4e-16);
  }
}
