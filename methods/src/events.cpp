#include "mbsflow/methods/events.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mbsflow/error.hpp"

namespace mbsflow {

EventDetector::EventDetector(std::vector<EventFunction> functions, double time_tol)
    : functions_(std::move(functions)), time_tol_(time_tol) {
  for (const EventFunction& f : functions_) {
    if (!f.g) throw InputError("event '" + f.name + "' has no function");
    if (f.direction < -1 || f.direction > 1) throw InputError("event '" + f.name + "': direction must be -1, 0 or 1");
  }
  if (!(time_tol_ >= 0)) throw InputError("events: time_tol must be >= 0");
}

void EventDetector::reset(const Stepper& s) {
  g_.resize(functions_.size());
  for (std::size_t k = 0; k < functions_.size(); ++k) g_[k] = functions_[k].g(s.t(), s.y());
}

// Illinois: regula falsi whose retained end has its g halved each time it is kept twice
// in a row, so the bracket shrinks from both sides (superlinear, never slower than bisection
// by much). [ta, tb] with g(ta) = ga and g(tb) = gb of opposite signs (or gb = 0).
Event EventDetector::locate(const Stepper& s, std::size_t k, double ga, double gb) const {
  const EventFunction& f = functions_[k];
  double ta = s.t_previous(), tb = s.t();
  const double width = time_tol_ > 0 ? time_tol_
                                     : 8 * std::numeric_limits<double>::epsilon() * std::max(std::abs(tb), tb - ta);
  Eigen::VectorXd y;
  int kept = 0;  // +1: a kept twice in a row, -1: b
  for (int iteration = 0; iteration < 200 && tb - ta > width && gb != 0; ++iteration) {
    double t = tb - gb * (tb - ta) / (gb - ga);
    // Inside the bracket, at least a fraction of the width from either end.
    t = std::clamp(t, ta + 0.5 * width, tb - 0.5 * width);
    s.dense(t, y);
    const double g = f.g(t, y);
    if ((g > 0) == (gb > 0) || g == 0) {  // the new sign is already at t: [ta, t]
      tb = t;
      gb = g;
      if (kept == 1) ga *= 0.5;
      kept = 1;
    } else {
      ta = t;
      ga = g;
      if (kept == -1) gb *= 0.5;
      kept = -1;
    }
  }
  Event e;
  e.index = k;
  e.t = tb;
  e.direction = ga < 0 ? 1 : -1;
  if (tb == s.t())
    e.y = s.y();
  else
    s.dense(tb, e.y);
  return e;
}

std::vector<Event> EventDetector::after_step(const Stepper& s) {
  if (g_.size() != functions_.size()) throw InputError("events: reset() before the first step");
  std::vector<Event> found;
  for (std::size_t k = 0; k < functions_.size(); ++k) {
    const double ga = g_[k], gb = functions_[k].g(s.t(), s.y());
    g_[k] = gb;
    // A zero at the step's start was the last step's event; a sign change is one now.
    const bool rising = ga < 0 && gb >= 0, falling = ga > 0 && gb <= 0;
    const int direction = functions_[k].direction;
    if ((rising && direction >= 0) || (falling && direction <= 0)) found.push_back(locate(s, k, ga, gb));
  }
  std::sort(found.begin(), found.end(), [](const Event& a, const Event& b) { return a.t < b.t; });
  const auto terminal = std::find_if(found.begin(), found.end(), [&](const Event& e) { return functions_[e.index].terminal; });
  if (terminal != found.end()) found.erase(terminal + 1, found.end());
  return found;
}

std::vector<Event> integrate_with_events(Stepper& s, EventDetector& events) {
  std::vector<Event> all;
  events.reset(s);
  while (!s.done()) {
    s.step();
    const std::vector<Event> found = events.after_step(s);
    all.insert(all.end(), found.begin(), found.end());
    if (!found.empty() && events.is_terminal(found.back().index)) {
      // The run ends at the event: the stepper restarts there, so it can go on from it.
      s.start(found.back().t, found.back().y, s.t_end());
      events.reset(s);
      break;
    }
  }
  return all;
}

}  // namespace mbsflow
