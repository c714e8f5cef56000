// Simulation: a model stepped by the embedding program (simulation.hpp).
#include <cmath>

#include "mbsflow/runtime/divergence.hpp"
#include "multibody_stepper.hpp"
#include "sink_runner.hpp"

namespace mbsflow {

// A load the program holds on one body: a force element whose wrench it sets.
struct Simulation::HeldLoad final : ForceElement {
  int body = 0;
  Wrench wrench;
  std::vector<int> bodies() const override { return {body}; }
  void evaluate(double, const Kinematics&, std::span<Wrench> out) const override { out[0] = wrench; }
  bool constant_wrench() const override { return true; }  // between changes, which restart the method
};

namespace {

// The stepper's view of a system the program may add force elements to between steps:
// its stages take turns on the system itself, since copies made for concurrent stages
// (StepperSystem::another_rhs) would not see an element added later.
StepperSystem changing_stepper_system(MultibodySystem& sys, const std::string& jacobian) {
  StepperSystem s = stepper_system(sys, jacobian);
  s.another_rhs = nullptr;
  return s;
}

}  // namespace

Simulation::Simulation(const Model& model) : Simulation(model, options_from_model(model)) {}

Simulation::Simulation(const Model& model, const RunOptions& options)
    : system_(std::make_unique<MultibodySystem>(model)), o_(options) {
  check_options(o_);
  stepper_system_ = changing_stepper_system(*system_, o_.jacobian);
  stepper_ = stepper_entry(o_.method).make(stepper_system_, stepper_settings(o_));
  stepper_->start(o_.t_start, system_->initial_state(), o_.t_end);
}

Simulation::~Simulation() = default;

void Simulation::add_force_element(std::shared_ptr<const ForceElement> element) {
  system_->add_force_element(std::move(element));
  restart_ = true;
  if (stepper_system_.jacobian && !system_->has_analytic_jacobian()) {
    // The element has no analytic Jacobian: a stepper that differences (its counters restart).
    const double t = stepper_->t(), t_end = stepper_->t_end();
    const Eigen::VectorXd y = stepper_->y();
    stepper_system_ = changing_stepper_system(*system_, o_.jacobian);
    stepper_ = stepper_entry(o_.method).make(stepper_system_, stepper_settings(o_));
    stepper_->start(t, y, t_end);
  }
}

void Simulation::set_load(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  if (body < 0 || body >= system_->layout().bodies)
    throw InputError("set_load: body index " + std::to_string(body) + " out of range");
  if (!force.allFinite() || !torque.allFinite()) throw InputError("set_load: the force and torque must be finite");
  if (loads_.empty()) loads_.resize(static_cast<std::size_t>(system_->layout().bodies));
  std::shared_ptr<HeldLoad>& load = loads_[static_cast<std::size_t>(body)];
  if (!load) {
    load = std::make_shared<HeldLoad>();
    load->body = body;
    add_force_element(load);
  }
  load->wrench = {force, torque};
  restart_ = true;
}

void Simulation::ready(double t_end) {
  if (restart_ || t_end != stepper_->t_end()) stepper_->start(stepper_->t(), stepper_->y(), t_end);
  restart_ = false;
}

void Simulation::take_step() {
  check_stop(o_, stepper_->t());
  stepper_->step();
  check_diverged(*system_, stepper_->y(), stepper_->t(), o_);
}

bool Simulation::step() {
  ready(std::max(o_.t_end, stepper_->t()));
  if (stepper_->done()) return false;
  take_step();
  return true;
}

void Simulation::advance_to(double t) {
  if (!(t >= stepper_->t()) || !std::isfinite(t)) throw InputError("advance_to: the time must be finite and not in the past");
  if (t == stepper_->t()) return;
  ready(t);
  while (!stepper_->done()) take_step();
}

double Simulation::time() const { return stepper_->t(); }
const Eigen::VectorXd& Simulation::state() const { return stepper_->y(); }
const StepperStats& Simulation::stats() const { return stepper_->stats(); }

BodyState Simulation::body(int i) const {
  if (i < 0 || i >= system_->layout().bodies) throw InputError("body index " + std::to_string(i) + " out of range");
  const StateLayout& l = system_->layout();
  const Eigen::VectorXd& y = state();
  BodyState b;
  b.position = y.segment<3>(l.position(i));
  b.velocity = y.segment<3>(l.velocity(i));
  const Eigen::Vector4d q = y.segment<4>(l.orientation(i));
  b.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  b.angular_velocity = b.orientation * Eigen::Vector3d(y.segment<3>(l.angular_velocity(i)));
  return b;
}

void Simulation::set_state(const Eigen::VectorXd& y) {
  if (y.size() != system_->dimension()) throw InputError("set_state: the state has the wrong size");
  Eigen::VectorXd x = y;
  system_->after_step(stepper_->t(), x);
  stepper_->start(stepper_->t(), x, stepper_->t_end());
  restart_ = false;
}

}  // namespace mbsflow
