#pragma once
// Events: the zeros of user functions g(t, y) along a solution, found in every accepted
// step of any stepper on its dense output (so every method has them, and events do not
// shorten the steps), with a direction (rising, falling or both) and terminal or not.
// A zero is located by the Illinois variant of regula falsi to a bracket of time_tol.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {

struct EventFunction {
  std::string name;
  std::function<double(double t, const Eigen::VectorXd& y)> g;
  // +1: only where g rises through zero (from < 0 to >= 0); -1: only where it falls (from
  // > 0 to <= 0); 0: both.
  int direction = 0;
  bool terminal = false;  // the integration stops at the first such event
};

struct Event {
  std::size_t index = 0;  // of the function in the list
  double t = 0;           // the end of the final bracket: g has its new sign there
  Eigen::VectorXd y;      // the dense output at t
  int direction = 0;      // +1 rising, -1 falling
};

// Watches the functions over a stepper's steps.
class EventDetector {
 public:
  // time_tol: the width of the final bracket (0: 8 eps max(|t|, step)).
  explicit EventDetector(std::vector<EventFunction> functions, double time_tol = 0);
  // The values of g at the stepper's current point (after start(); again after any
  // restart or change of state between steps).
  void reset(const Stepper& s);
  // After an accepted step: the events in (t_previous, t], in time order, up to and
  // including the first terminal one.
  std::vector<Event> after_step(const Stepper& s);
  bool is_terminal(std::size_t k) const { return functions_[k].terminal; }

 private:
  Event locate(const Stepper& s, std::size_t k, double ga, double gb) const;

  std::vector<EventFunction> functions_;
  double time_tol_;
  std::vector<double> g_;  // at the stepper's t
};

// Steps `s` from its current point to its t_end, collecting the events. At a terminal event
// the stepper is restarted at the event (t(), y() are the event's), so it can go on.
std::vector<Event> integrate_with_events(Stepper& s, EventDetector& events);

}  // namespace mbsflow
