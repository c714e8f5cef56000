#pragma once
// Detects a state that has become non-finite or has blown up.
#include <optional>
#include <string>

#include "mbsflow/graph/multibody_system.hpp"
#include "mbsflow/methods/dopri5.hpp"  // step_collapsed_message

namespace mbsflow {

struct Divergence {
  int body = -1;
  std::string what;  // e.g. "state is not finite", "speed 3.1e+09 m/s"
};

// Speeds beyond these are taken as a blow-up: no machine part moves that fast.
inline constexpr double divergence_speed = 1e6;          // m/s
inline constexpr double divergence_angular_speed = 1e7;  // rad/s

// Looks at the first `bodies` bodies of the layout (-1: all), e.g. a submodel's own bodies:
// first for a non-finite value, then for a blow-up.
std::optional<Divergence> find_divergence(const StateLayout& layout, const Eigen::VectorXd& y, Eigen::Index bodies = -1);

// What unknown i of a model's state is, with the joints at its body, stiffest first:
// "the velocity (y) of body 'link3' (joints 'j4', 'j3')". For failure messages.
std::string describe_unknown(const Model& model, Eigen::Index i);

// The message of a diverged run: time, body, and a step that would work.
std::string divergence_message(const Model& model, const Divergence& d, double t, Method method, double step);
// The same for a loosely coupled run (loose_coupling.hpp), where the coupling is the
// likely cause unless the RK4 step itself is beyond the stability limit. `overlap`: the
// run's overlap reach (s). The advice: with a lag, none (a lag rules out the overlap);
// with an overlap shorter than the macro step, one macro step of overlap; else twice it.
std::string loose_divergence_message(const Model& model, const Divergence& d, double t, Method method, double step,
                                     double macro_step, int lag, double overlap);

}  // namespace mbsflow
