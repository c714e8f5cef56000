// Lanes (graph/src/lanes.hpp) carry the right-hand side's bushings and free bodies several
// at a time. What a lane computes must depend on its own item alone, whatever the other
// lanes hold: then a run is bitwise identical whichever items a partition groups together.
// Checked lane by lane against the same item in every lane, with lanes that take different
// branches side by side, and on a whole system evaluated at once and item by item in
// shuffled order. Against the double code a lane agrees to rounding, not bit for bit:
// Eigen sums a custom scalar's dot products in another order (x0 + (x1 + x2)).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "force_laws.hpp"
#include "lanes.hpp"
#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/graph/simd.hpp"
#include "rotation.hpp"

using namespace mbsflow;

namespace {

constexpr int W = Lanes::width;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A rotation by an angle drawn from one of the ranges rotation_log treats apart (zero,
// below 1e-7, the series of small_atan2, libm's atan2 up to pi), as q or -q.
Eigen::Vector4d random_rotation(std::mt19937& g, int range) {
  std::normal_distribution<double> n;
  const double top[] = {0.0, 1e-8, 0.45, 3.1};
  const double angle = std::uniform_real_distribution<double>(0.0, 1.0)(g) * top[range % 4];
  const Eigen::Vector3d axis = Eigen::Vector3d(n(g), n(g), n(g)).normalized();
  Eigen::Vector4d q;
  q << std::cos(angle / 2), std::sin(angle / 2) * axis;
  return (g() % 2 ? -1.0 : 1.0) * q;
}

Eigen::Vector3d random_vector(std::mt19937& g, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(g), u(g), u(g)};
}

BushingParams<double> random_bushing(std::mt19937& g, bool frame1, bool frame2) {
  BushingParams<double> j;
  j.frame1_identity = !frame1;
  j.frame2_identity = !frame2;
  j.qfa = frame1 ? random_rotation(g, 2) : Eigen::Vector4d(1, 0, 0, 0);
  j.qfb = frame2 ? random_rotation(g, 3) : Eigen::Vector4d(1, 0, 0, 0);
  j.rfa = rotation_matrix(j.qfa);
  j.pa = random_vector(g, 0.5);
  j.pb = random_vector(g, 0.5);
  j.kt = random_vector(g, 1e6).cwiseAbs();
  j.ct = random_vector(g, 1e3).cwiseAbs();
  j.kr = random_vector(g, 1e4).cwiseAbs();
  j.cr = random_vector(g, 10).cwiseAbs();
  j.preload_force = random_vector(g, 10);
  j.preload_torque = random_vector(g, 1);
  return j;
}

BodyFrameT<double> random_frame(std::mt19937& g, int range) {
  return body_frame<double>(random_vector(g, 2), random_rotation(g, range), random_vector(g, 3), random_vector(g, 5));
}

// Bushings of every frame class, springs and a table between 23 tumbling bodies, one of
// them driven.
Model mixed_model(std::mt19937& g) {
  Model m;
  m.gravity = {0.0, 0.0, -9.81};
  const int n = 23;
  for (int i = 0; i < n; ++i) {
    Body b;
    b.name = "b" + std::to_string(i);
    b.mass = 1.0 + 0.1 * i;
    b.inertia = {0.1 + 0.01 * i, 0.2, 0.15, 0.01, -0.02, 0.005};
    b.position = {0.5 * i, 0.01 * i, 0.0};
    const Eigen::Vector4d q = random_rotation(g, 2);
    b.orientation = {q[0], q[1], q[2], q[3]};
    const Eigen::Vector3d w = random_vector(g, 3), v = random_vector(g, 1);
    b.angular_velocity = {w[0], w[1], w[2]};
    b.velocity = {v[0], v[1], v[2]};
    m.bodies.push_back(b);
  }
  for (int i = 0; i < n; ++i) {  // every frame class, springs and a table between
    Joint j;
    j.name = "j" + std::to_string(i);
    j.body1 = i == 0 ? ground : i - 1;
    j.body2 = i;
    j.point1 = {0.25, 0.0, 0.0};
    j.point2 = {-0.25, 0.0, 0.0};
    j.stiffness = {1e5, 2e5, 3e5, 1e3, 2e3, 3e3};
    j.damping = {10, 20, 30, 1, 2, 3};
    j.preload = {0.0, 0.0, 1.0, 0.0, 0.1, 0.0};
    if (i % 3 == 1) j.frame1 = {std::cos(0.2), std::sin(0.2), 0.0, 0.0};
    if (i % 5 == 2) j.frame2 = {std::cos(0.3), 0.0, 0.0, std::sin(0.3)};
    if (i % 7 == 6) {
      j.type = JointType::spring;
      j.rest_length = 0.4;
    }
    if (i == 10) j.tables[4] = ForceTable{{-1.0, 0.0, 1.0}, {-500.0, 0.0, 2000.0}};
    m.joints.push_back(j);
  }
  Driver d;
  d.body = 4;
  d.velocity = {0.1, 0.0, 0.0};
  m.drivers.push_back(d);
  return m;
}

// mixed_model's bodies and driver with bushings only, no frame turned, no spring or table:
// nothing reads a stored rotation matrix. Bodies come four to a mass and inertia, so that
// lane groups hold one body law or several.
Model bushings_only(std::mt19937& g) {
  Model m = mixed_model(g);
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    m.bodies[i].mass = 1.0 + 0.1 * static_cast<double>(i / 4);
    m.bodies[i].inertia = {0.1 + 0.01 * static_cast<double>(i / 4), 0.2, 0.15, 0.01, -0.02, 0.005};
  }
  for (Joint& j : m.joints) {
    j.type = JointType::bushing;
    j.frame1 = j.frame2 = {1.0, 0.0, 0.0, 0.0};
    j.tables = {};
  }
  return m;
}


}  // namespace

TEST_CASE("lanes: the rotation logarithm of a lane depends on its own quaternion alone", "[graph]") {
  std::mt19937 g(7);
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Vector4d q[W];
    for (int l = 0; l < W; ++l) q[l] = random_rotation(g, static_cast<int>(g() % 4));  // lanes on different branches
    const RotationLogT<Lanes> mixed = rotation_log<Lanes>(gather([&](int l) -> auto& { return q[l]; }));
    for (int l = 0; l < W; ++l) {
      const RotationLogT<Lanes> alone = rotation_log<Lanes>(gather([&](int) -> auto& { return q[l]; }));
      const RotationLog one = rotation_log(q[l]);
      for (int k = 0; k < 3; ++k) {
        REQUIRE(same_bits(mixed.theta[k].v[l], alone.theta[k].v[0]));
        REQUIRE(std::abs(mixed.theta[k].v[l] - one.theta[k]) <= 1e-15 * std::max(1.0, one.theta.norm()));
      }
      REQUIRE(same_bits(mixed.c.v[l], alone.c.v[0]));
      // c = 1/angle^2 - cot(angle/2)/(2 angle) cancels: its rounding is that of 1/angle^2
      REQUIRE(std::abs(mixed.c.v[l] - one.c) <= 1e-14 * std::max(std::abs(one.c), 1.0 / one.theta.squaredNorm()));
    }
  }
}

TEST_CASE("lanes: a bushing's wrench in a lane depends on its own joint alone", "[graph]") {
  std::mt19937 g(11);
  for (int trial = 0; trial < 2000; ++trial) {
    const bool frame1 = trial % 2, frame2 = (trial / 2) % 2;  // a group shares its frame class
    BushingParams<double> j[W];
    BodyFrameT<double> a[W], b[W];
    for (int l = 0; l < W; ++l) {
      j[l] = random_bushing(g, frame1, frame2);
      a[l] = random_frame(g, 3);
      b[l] = random_frame(g, static_cast<int>(g() % 4));
      if (g() % 3 == 0) b[l].quat = a[l].quat;  // no relative rotation at all
    }
    using B = BushingParams<double>;
    const auto of = [&](auto field) { return gather([&](int l) -> auto& { return j[l].*field; }); };
    BushingParams<Lanes> jl;
    jl.frame1_identity = !frame1;
    jl.frame2_identity = !frame2;
    jl.rfa = of(&B::rfa);
    jl.qfa = of(&B::qfa);
    jl.qfb = of(&B::qfb);
    jl.pa = of(&B::pa);
    jl.pb = of(&B::pb);
    jl.kt = of(&B::kt);
    jl.ct = of(&B::ct);
    jl.kr = of(&B::kr);
    jl.cr = of(&B::cr);
    jl.preload_force = of(&B::preload_force);
    jl.preload_torque = of(&B::preload_torque);
    const auto frames = [&](const BodyFrameT<double>* f) {
      const auto field = [&](auto member) { return gather([&](int l) -> auto& { return f[l].*member; }); };
      using F = BodyFrameT<double>;
      return BodyFrameT<Lanes>{field(&F::rot), field(&F::pos), field(&F::vel), field(&F::omega), field(&F::quat)};
    };
    Eigen::Matrix<Lanes, 9, 1> mixed;
    compliant_joint_wrench<Lanes>(jl, nullptr, frames(a), frames(b), mixed);
    for (int l = 0; l < W; ++l) {
      // lane l's joint and bodies in every lane
      BushingParams<Lanes> jl_alone = jl;
      const auto broadcast = [&](auto& m) {
        for (Eigen::Index c = 0; c < m.size(); ++c) m.data()[c] = Lanes(m.data()[c].v[l]);
      };
      for (auto* m : {&jl_alone.pa, &jl_alone.pb, &jl_alone.kt, &jl_alone.ct, &jl_alone.kr, &jl_alone.cr, &jl_alone.preload_force,
                      &jl_alone.preload_torque})
        broadcast(*m);
      broadcast(jl_alone.rfa);
      broadcast(jl_alone.qfa);
      broadcast(jl_alone.qfb);
      BodyFrameT<Lanes> fa = frames(a), fb = frames(b);
      for (BodyFrameT<Lanes>* f : {&fa, &fb}) {
        broadcast(f->rot);
        broadcast(f->pos);
        broadcast(f->vel);
        broadcast(f->omega);
        broadcast(f->quat);
      }
      Eigen::Matrix<Lanes, 9, 1> alone;
      compliant_joint_wrench<Lanes>(jl_alone, nullptr, fa, fb, alone);
      Eigen::Matrix<double, 9, 1> one;
      compliant_joint_wrench<double>(j[l], nullptr, a[l], b[l], one);
      for (int r = 0; r < 9; ++r) {
        REQUIRE(same_bits(mixed[r].v[l], alone[r].v[0]));
        const double scale = one.segment<3>(r / 3 * 3).norm();
        REQUIRE(std::abs(mixed[r].v[l] - one[r]) <= 1e-12 * scale);
      }
    }
  }
}

TEST_CASE("lanes: a system evaluated at once and item by item in shuffled groups agrees bit for bit", "[graph]") {
  const Simd before = simd();
  for (const Simd kind : {Simd::sse2, Simd::avx}) {
    if (!set_simd(kind)) {
      WARN("this CPU has no AVX: the AVX kernels are not run");
      continue;
    }
    std::mt19937 g(5);
    for (const Model& m : {mixed_model(g), bushings_only(g)}) {
    const int n = static_cast<int>(m.bodies.size());
    MultibodySystem whole(m), items(m);
    Eigen::VectorXd y = whole.initial_state(), expected(whole.dimension()), got(whole.dimension());
    y += 1e-3 * Eigen::VectorXd::Random(y.size());  // every bushing deflected
    whole.rhs(0.3, y, expected);

    std::vector<int> bodies(static_cast<std::size_t>(n)), joints(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) bodies[static_cast<std::size_t>(i)] = joints[static_cast<std::size_t>(i)] = i;
    for (int trial = 0; trial < 20; ++trial) {
      std::shuffle(bodies.begin(), bodies.end(), g);
      std::shuffle(joints.begin(), joints.end(), g);
      const std::size_t cut = 1 + g() % static_cast<std::size_t>(n - 1);  // two groups of items, as two partitions
      const std::span<const int> b(bodies), j(joints);
      got.setConstant(NAN);
      items.kinematics_of(0.3, y, b.subspan(cut));
      items.kinematics_of(0.3, y, b.first(cut));
      items.joint_forces_of(j.first(cut));
      items.joint_forces_of(j.subspan(cut));
      items.derivatives_of(0.3, y, got, b.subspan(cut));
      items.derivatives_of(0.3, y, got, b.first(cut));
      for (Eigen::Index k = 0; k < got.size(); ++k) REQUIRE(same_bits(got[k], expected[k]));
    }
    }
  }
  set_simd(before);
}

TEST_CASE("lanes: free bodies' rates agree with the rigid-body equations to rounding", "[graph]") {
  // Tumbling bodies without joints, two inertias among them: v' = g, J w' = -w x J w,
  // q' = q (x) (0, w) / 2, computed here in double.
  const Simd before = simd();
  for (const Simd kind : {Simd::sse2, Simd::avx}) {
    if (!set_simd(kind)) continue;
    std::mt19937 g(11);
    Model m;
    m.gravity = {0.3, -0.2, -9.81};
    for (int i = 0; i < 7; ++i) {
      Body b;
      b.name = "b" + std::to_string(i);
      b.mass = i % 3 == 0 ? 2.0 : 0.5;
      b.inertia = i % 3 == 0 ? Vec6{0.3, 0.2, 0.1, 0.01, 0.02, -0.03} : Vec6{0.05, 0.07, 0.09, 0.0, 0.0, 0.0};
      const Eigen::Vector4d q = random_rotation(g, 3);
      b.orientation = {q[0], q[1], q[2], q[3]};
      const Eigen::Vector3d w = random_vector(g, 4);
      b.angular_velocity = {w[0], w[1], w[2]};
      b.velocity = {0.1 * i, 0.0, 0.0};
      m.bodies.push_back(b);
    }
    MultibodySystem sys(m);
    const Eigen::VectorXd y = sys.initial_state();
    Eigen::VectorXd dydt(sys.dimension());
    sys.rhs(0.0, y, dydt);
    const StateLayout& l = sys.layout();
    for (Eigen::Index i = 0; i < l.bodies; ++i) {
      const Body& b = m.bodies[static_cast<std::size_t>(i)];
      Eigen::Matrix3d inertia;
      inertia << b.inertia[0], b.inertia[3], b.inertia[4], b.inertia[3], b.inertia[1], b.inertia[5], b.inertia[4], b.inertia[5],
          b.inertia[2];
      const Eigen::Vector3d w = y.segment<3>(l.angular_velocity(i));
      const Eigen::Vector4d q = y.segment<4>(l.orientation(i));
      const Eigen::Vector3d w_rate = inertia.inverse() * (-w.cross(inertia * w));
      const Eigen::Vector4d q_rate = 0.5 * quat_multiply(q, Eigen::Vector4d(0.0, w[0], w[1], w[2]));
      CHECK((dydt.segment<3>(l.position(i)) - y.segment<3>(l.velocity(i))).norm() == 0.0);
      CHECK((dydt.segment<3>(l.velocity(i)) - Eigen::Vector3d(0.3, -0.2, -9.81)).norm() <= 1e-15 * 9.81);
      CHECK((dydt.segment<3>(l.angular_velocity(i)) - w_rate).norm() <= 1e-13 * (1.0 + w_rate.norm()));
      CHECK((dydt.segment<4>(l.orientation(i)) - q_rate).norm() <= 1e-15 * (1.0 + q_rate.norm()));
    }
  }
  set_simd(before);
}

TEST_CASE("lanes: the AVX and SSE2 kernels give the same right-hand side bit for bit", "[graph]") {
  const Simd before = simd();
  std::mt19937 g(9);
  const Model m = mixed_model(g);
  MultibodySystem sys(m);
  std::vector<Eigen::VectorXd> states;  // growing deflections
  Eigen::VectorXd dydt(sys.dimension());
  for (int i = 0; i < 40; ++i) states.push_back(sys.initial_state() + (0.002 * i) * Eigen::VectorXd::Random(dydt.size()));
  const auto derivatives = [&] {
    std::vector<Eigen::VectorXd> out;
    for (std::size_t i = 0; i < states.size(); ++i) {
      sys.rhs(0.01 * static_cast<double>(i), states[i], dydt);
      out.push_back(dydt);
    }
    return out;
  };
  REQUIRE(set_simd(Simd::sse2));
  const std::vector<Eigen::VectorXd> sse2 = derivatives();
  if (!set_simd(Simd::avx)) {
    WARN("this CPU has no AVX: nothing to compare");
    return;
  }
  const std::vector<Eigen::VectorXd> avx = derivatives();
  set_simd(before);
  for (std::size_t i = 0; i < states.size(); ++i)
    for (Eigen::Index k = 0; k < sse2[i].size(); ++k) {
      INFO("state " << i << " entry " << k << ": " << sse2[i][k] << " vs " << avx[i][k]);
      REQUIRE(std::isfinite(sse2[i][k]));
      REQUIRE(same_bits(sse2[i][k], avx[i][k]));
    }
}
