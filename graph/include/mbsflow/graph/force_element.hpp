#pragma once
// User-defined force elements: the extension point of the mechanics for forces that the
// model format does not describe (tyres, contact, aerodynamics, controllers...).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <span>
#include <vector>

#include "mbsflow/error.hpp"

namespace mbsflow {

// Read-only kinematics of the bodies at the current evaluation, world frame, by model body
// index. A force element reads only its own bodies(): in a partitioned run it is evaluated
// in a submodel that holds just those (and then asking for another body throws).
class Kinematics {
 public:
  Kinematics(const std::vector<Eigen::Matrix3d>& rotation, const Eigen::Matrix3Xd& position,
             const Eigen::Matrix3Xd& velocity, const Eigen::Matrix3Xd& angular_velocity)
      : rot_(rotation), pos_(position), vel_(velocity), omega_(angular_velocity) {}
  // A view of k in which model body model_bodies[i] is k's body local_bodies[i] (a submodel).
  Kinematics(const Kinematics& k, std::span<const int> model_bodies, std::span<const int> local_bodies)
      : rot_(k.rot_), pos_(k.pos_), vel_(k.vel_), omega_(k.omega_), from_(model_bodies), to_(local_bodies) {}
  const Eigen::Matrix3d& rotation(int body) const { return rot_[static_cast<std::size_t>(at(body))]; }  // body to world
  Eigen::Vector3d position(int body) const { return pos_.col(at(body)); }  // centre of mass
  Eigen::Vector3d velocity(int body) const { return vel_.col(at(body)); }
  Eigen::Vector3d angular_velocity(int body) const { return omega_.col(at(body)); }  // world frame
  // World position and velocity of a point given in the body frame.
  Eigen::Vector3d point(int body, const Eigen::Vector3d& local) const { return position(body) + rotation(body) * local; }
  Eigen::Vector3d point_velocity(int body, const Eigen::Vector3d& local) const {
    return velocity(body) + angular_velocity(body).cross(rotation(body) * local);
  }

 private:
  int at(int body) const {
    if (from_.empty()) return body;
    const auto i = std::find(from_.begin(), from_.end(), body);
    if (i == from_.end())
      throw InputError("force element: read body " + std::to_string(body) + ", which is not one of its bodies()");
    return to_[static_cast<std::size_t>(i - from_.begin())];
  }
  const std::vector<Eigen::Matrix3d>& rot_;
  const Eigen::Matrix3Xd &pos_, &vel_, &omega_;
  std::span<const int> from_, to_;  // model body -> index here; empty: the same
};

struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // world frame
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // world frame, about the body's centre of mass
};

class ForceElement {
 public:
  virtual ~ForceElement() = default;
  // The bodies it acts on and reads (model body indices), fixed for the life of the system.
  virtual std::vector<int> bodies() const = 0;
  // Sets out[i] to the wrench on bodies()[i]. Must depend only on t and k, so that a run is
  // deterministic. Each body adds element wrenches after its joints, in element order.
  virtual void evaluate(double t, const Kinematics& k, std::span<Wrench> out) const = 0;
  // Energy the element stores, if it is conservative (for energy balances); 0 otherwise.
  virtual double energy(double /*t*/, const Kinematics& /*k*/) const { return 0.0; }
  // True for an element whose wrenches depend on neither t nor the state, as a held load's
  // (Simulation::set_load): the analytic Jacobian then covers it (a world-frame torque
  // acts through the body's orientation, as a model load's does), where any other element
  // makes the implicit methods difference their Jacobian.
  virtual bool constant_wrench() const { return false; }
};

}  // namespace mbsflow
