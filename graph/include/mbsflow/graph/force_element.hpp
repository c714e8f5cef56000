#pragma once
// User-defined force elements: the extension point of the mechanics for forces that the
// model format does not describe (tyres, contact, aerodynamics, controllers...).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>
#include <vector>

namespace mbsflow {

// Read-only kinematics of every body at the current evaluation, world frame.
class Kinematics {
 public:
  Kinematics(const std::vector<Eigen::Matrix3d>& rotation, const Eigen::Matrix3Xd& position,
             const Eigen::Matrix3Xd& velocity, const Eigen::Matrix3Xd& angular_velocity)
      : rot_(rotation), pos_(position), vel_(velocity), omega_(angular_velocity) {}
  const Eigen::Matrix3d& rotation(int body) const { return rot_[static_cast<std::size_t>(body)]; }  // body to world
  Eigen::Vector3d position(int body) const { return pos_.col(body); }          // centre of mass
  Eigen::Vector3d velocity(int body) const { return vel_.col(body); }
  Eigen::Vector3d angular_velocity(int body) const { return omega_.col(body); }  // world frame
  // World position and velocity of a point given in the body frame.
  Eigen::Vector3d point(int body, const Eigen::Vector3d& local) const { return position(body) + rotation(body) * local; }
  Eigen::Vector3d point_velocity(int body, const Eigen::Vector3d& local) const {
    return velocity(body) + angular_velocity(body).cross(rotation(body) * local);
  }

 private:
  const std::vector<Eigen::Matrix3d>& rot_;
  const Eigen::Matrix3Xd &pos_, &vel_, &omega_;
};

struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // world frame
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // world frame, about the body's centre of mass
};

class ForceElement {
 public:
  virtual ~ForceElement() = default;
  // The bodies it acts on (model body indices), fixed for the life of the system.
  virtual std::vector<int> bodies() const = 0;
  // Sets out[i] to the wrench on bodies()[i]. Must depend only on t and k, so that a run is
  // deterministic. Each body adds element wrenches after its joints, in element order.
  virtual void evaluate(double t, const Kinematics& k, std::span<Wrench> out) const = 0;
  // Energy the element stores, if it is conservative (for energy balances); 0 otherwise.
  virtual double energy(double /*t*/, const Kinematics& /*k*/) const { return 0.0; }
};

}  // namespace mbsflow
