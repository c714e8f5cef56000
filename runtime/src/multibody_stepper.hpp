#pragma once
// A multibody system as what a stepper integrates: its rhs, and after every step the
// renormalised quaternions and prescribed motions. MultibodySystem::rhs works in the
// system's own scratch (kinematics, joint forces), so calls are serialised: the implicit
// methods evaluate their stages from several flow-graph nodes at once, and unserialised
// calls raced (ThreadSanitizer) and made colloc/tirk runs differ from run to run.
#include <memory>
#include <mutex>

#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

inline StepperSystem stepper_system(MultibodySystem& sys) {
  StepperSystem s;
  s.size = sys.dimension();
  s.rhs = [&sys, busy = std::make_shared<std::mutex>()](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    std::lock_guard lock(*busy);
    sys.rhs(t, y, dydt);
  };
  s.after_step = [&sys](double t, Eigen::VectorXd& y) { sys.after_step(t, y); };
  return s;
}

}  // namespace mbsflow
