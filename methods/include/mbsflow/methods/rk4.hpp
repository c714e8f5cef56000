#pragma once
// Classic fourth-order Runge-Kutta with a fixed step.
#include "mbsflow/methods/ode_system.hpp"

namespace mbsflow {

// The arithmetic of RK4, element by element, shared by the sequential stepper below and
// the partitioned executors: whoever computes a part of the state with these gets bit for
// bit the numbers of the whole-state computation.
namespace rk4 {
inline constexpr double stage_fraction[4] = {0.0, 0.5, 0.5, 1.0};  // c_i

// Input of stage s+1 (s = 0, 1, 2): y + c_{s+1} h k_s.
template <class Y, class K, class Out>
void stage_input(const Y& y, const K& k, double h, int s, Out&& out) {
  out = y + (stage_fraction[s + 1] * h) * k;
}

// y_{n+1} = y_n + h/6 (((k1 + 2 k2) + 2 k3) + k4), in place: the sums in the order in
// which the stages come, so that they can also be taken as they come (below).
template <class Y, class K>
void combine(Y&& y, const K& k1, const K& k2, const K& k3, const K& k4, double h) {
  y += (h / 6.0) * (((k1 + 2.0 * k2) + 2.0 * k3) + k4);
}

// combine taken as the stages come, so that two stage derivatives are kept instead of
// four: k1 is the sum; after k2 and after k3, accumulate sum <- sum + 2 k; after k4,
// finish y += h/6 (sum + k4). Element by element the same operations in the same order as
// combine, so the same numbers to the bit.
template <class Sum, class K>
void accumulate(Sum&& sum, const K& k) {
  sum = sum + 2.0 * k;
}
template <class Y, class K>
void finish(Y&& y, const K& sum, const K& k4, double h) {
  y += (h / 6.0) * (sum + k4);
}
}  // namespace rk4

class Rk4 {
 public:
  // Zeroed: the workspace's pages are touched here, in the set-up, not in the first step.
  explicit Rk4(Eigen::Index n) : sum_(Eigen::VectorXd::Zero(n)), k_(Eigen::VectorXd::Zero(n)), tmp_(Eigen::VectorXd::Zero(n)) {}

  // Advances y from t to t + h. Four evaluations of f: k1 starts the sum, k2 and k3 go
  // into it as they come (rk4::accumulate), so two derivatives are kept, not four.
  template <OdeSystem S>
  void step(S& sys, double t, double h, Eigen::VectorXd& y) {
    sys.rhs(t, y, sum_);
    for (int s = 0; s < 3; ++s) {
      rk4::stage_input(y, s == 0 ? sum_ : k_, h, s, tmp_);
      if (s > 0) rk4::accumulate(sum_, k_);
      sys.rhs(t + rk4::stage_fraction[s + 1] * h, tmp_, k_);
    }
    rk4::finish(y, sum_, k_, h);
  }

  static constexpr int evaluations_per_step = 4;
  static constexpr int order = 4;

 private:
  Eigen::VectorXd sum_, k_, tmp_;
};

}  // namespace mbsflow
