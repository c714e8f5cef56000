// The right-hand side's work on Lanes (lanes.hpp), Lanes::width items at a time:
// bushings without tables (the joints' phase, MultibodySystem::joint_forces_in) and the
// bodies' rotation matrices and world angular velocities (kinematics_in). (A free body's
// rates on Lanes, tried too, were no faster: gathering its two inertia matrices cost what
// the lanes saved.) This file is compiled twice:
// as it is for SSE2, two lanes, and by lane_kernels_avx.cpp for AVX, four lanes, with the
// _avx suffix on each kernel's name; no FMA in either, so both round alike.
//
// A bushing is most of a compliant model's work, and one at a time it is a long chain of
// dependent operations (quaternion product, norm, square root, arctangent, divisions) that
// leaves the core waiting. Several side by side run the same force_laws.hpp arithmetic in
// fewer instructions and hide each other's latency. Bushings are grouped by which of their
// joint frames is the identity (a group runs one code path); the last incomplete group
// repeats its last item. Each lane's numbers depend on its own item alone, so any order
// and grouping of the items, which differ between partitions, gives the same numbers bit
// for bit.
//
// Only Eigen objects of Lanes (whose type differs between the two builds) do arithmetic
// here: the double objects are read and written coefficient by coefficient, so that no
// double code built for AVX is shared with the rest of the library.
#include "mbsflow/graph/multibody_system.hpp"

#include "force_laws.hpp"
#include "lanes.hpp"
#include "rotation.hpp"

#ifdef MBSFLOW_LANE_KERNEL_SUFFIX
#define LANE_KERNEL(name) name##_avx
#else
#define LANE_KERNEL(name) name
#endif

namespace mbsflow {

void MultibodySystem::LANE_KERNEL(bushings_on_lanes)(const int* k) {
  const CompiledJoint* j[Lanes::width];
  const JointLaw* law[Lanes::width];
  for (int l = 0; l < Lanes::width; ++l) {
    j[l] = &compiled_->joints[static_cast<std::size_t>(k[l])];
    law[l] = &law_of(*j[l]);
  }
  // Repeated bushings (a chain's, a grid's) share one law: its numbers go to every lane.
  const bool one_law = one_item(law);
  const auto from_law = [&](auto field) { return lanes_of(law, one_law, field); };
  BushingParams<Lanes> p;
  p.frame1_identity = law[0]->frame1_identity;
  p.frame2_identity = law[0]->frame2_identity;
  p.pa = from_law(&JointLaw::pa);
  p.pb = from_law(&JointLaw::pb);
  p.kt = from_law(&JointLaw::kt);
  p.ct = from_law(&JointLaw::ct);
  p.kr = from_law(&JointLaw::kr);
  p.cr = from_law(&JointLaw::cr);
  p.preload_force = from_law(&JointLaw::preload_force);
  p.preload_torque = from_law(&JointLaw::preload_torque);
  if (!p.frame1_identity) {
    p.rfa = from_law(&JointLaw::rfa);
    p.qfa = from_law(&JointLaw::qfa);
  }
  if (!p.frame2_identity) p.qfb = from_law(&JointLaw::qfb);
  const auto frame = [&](int CompiledJoint::*body) {
    BodyFrameT<Lanes> f;
    f.quat = gather([&](int l) { return quat_.col(j[l]->*body); });
    f.rot = rotation_matrix<Lanes>(f.quat);  // as rot_ holds it, bit for bit, for fewer loads
    f.pos = gather([&](int l) { return pos_.col(j[l]->*body); });
    f.vel = gather([&](int l) { return vel_.col(j[l]->*body); });
    f.omega = gather([&](int l) { return omega_.col(j[l]->*body); });
    return f;
  };
  const BodyFrameT<Lanes> a = frame(&CompiledJoint::a), b = frame(&CompiledJoint::b);
  Eigen::Matrix<Lanes, 9, 1> out;
  compliant_joint_wrench<Lanes>(p, nullptr, a, b, out);
  scatter(out, [&](int l) { return joint_out_.col(k[l]); });
}


void MultibodySystem::LANE_KERNEL(kinematics_on_lanes)(const int* k, const Eigen::VectorXd& y, bool rotations) {
  const Vector4T<Lanes> q = gather([&](int l) { return y.segment<4>(layout_.orientation(k[l])); });
  const Vector3T<Lanes> w = gather([&](int l) { return y.segment<3>(layout_.angular_velocity(k[l])); });
  const Matrix3T<Lanes> r = rotation_matrix<Lanes>(q);
  if (rotations) scatter(r, [&](int l) -> auto& { return rot_[static_cast<std::size_t>(k[l])]; });
  scatter(Vector3T<Lanes>(r * w), [&](int l) { return omega_.col(k[l]); });
}

// The free bodies' rates, as write_derivative computes them but on lanes (so to rounding,
// not bit for bit, its numbers); the position rates, plain copies, are the caller's.
void MultibodySystem::LANE_KERNEL(rates_on_lanes)(const int* k, const double* wrench, const Eigen::VectorXd& y,
                                                  Eigen::VectorXd& dydt) const {
  const BodyLaw* law[Lanes::width];
  for (int l = 0; l < Lanes::width; ++l) law[l] = &body_law(static_cast<std::size_t>(k[l]));
  const bool one_law = one_item(law);
  Lanes inv_mass;
  for (int l = 0; l < Lanes::width; ++l) inv_mass.v[l] = law[l]->inv_mass;
  const Vector4T<Lanes> q = gather([&](int l) { return y.segment<4>(layout_.orientation(k[l])); });
  const Vector3T<Lanes> w = gather([&](int l) { return y.segment<3>(layout_.angular_velocity(k[l])); });
  const Vector3T<Lanes> force = gather([&](int l) { return Eigen::Map<const Eigen::Vector3d>(wrench + 6 * l); });
  const Vector3T<Lanes> torque = gather([&](int l) { return Eigen::Map<const Eigen::Vector3d>(wrench + 6 * l + 3); });
  const Matrix3T<Lanes> inertia = lanes_of(law, one_law, &BodyLaw::inertia);
  const Matrix3T<Lanes> inv_inertia = lanes_of(law, one_law, &BodyLaw::inv_inertia);
  const Matrix3T<Lanes> r = rotation_matrix<Lanes>(q);
  scatter(Vector3T<Lanes>(inv_mass * force), [&](int l) { return dydt.segment<3>(layout_.velocity(k[l])); });
  scatter(angular_acceleration<Lanes>(r, w, torque, inertia, inv_inertia),
          [&](int l) { return dydt.segment<3>(layout_.angular_velocity(k[l])); });
  scatter(quaternion_rate<Lanes>(q, w), [&](int l) { return dydt.segment<4>(layout_.orientation(k[l])); });
}

}  // namespace mbsflow
