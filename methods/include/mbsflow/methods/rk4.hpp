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

// y_{n+1} = y_n + h/6 (k1 + 2 (k2 + k3) + k4), in place.
template <class Y, class K>
void combine(Y&& y, const K& k1, const K& k2, const K& k3, const K& k4, double h) {
  y += (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4);
}

// combine in two parts, so that three stage derivatives are kept instead of four: after
// k3, fold k1 <- k1 + 2 (k2 + k3); after k4, finish y += h/6 (k1 + k4). Element by element
// the same operations in the same order as combine, so the same numbers to the bit.
template <class K1, class K>
void fold(K1&& k1, const K& k2, const K& k3) {
  k1 = k1 + 2.0 * (k2 + k3);
}
template <class Y, class K>
void finish(Y&& y, const K& folded, const K& k4, double h) {
  y += (h / 6.0) * (folded + k4);
}
}  // namespace rk4

class Rk4 {
 public:
  // Zeroed: the workspace's pages are touched here, in the set-up, not in the first step.
  explicit Rk4(Eigen::Index n)
      : k_{Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)}, tmp_(Eigen::VectorXd::Zero(n)) {}

  // Advances y from t to t + h. Four evaluations of f; k4 goes where k2 was, once k2 and
  // k3 are folded into k1 (rk4::fold), so three derivatives are kept, not four.
  template <OdeSystem S>
  void step(S& sys, double t, double h, Eigen::VectorXd& y) {
    sys.rhs(t, y, k_[0]);
    for (int s = 0; s < 3; ++s) {
      rk4::stage_input(y, k_[s], h, s, tmp_);
      if (s == 2) rk4::fold(k_[0], k_[1], k_[2]);
      sys.rhs(t + rk4::stage_fraction[s + 1] * h, tmp_, k_[s == 2 ? 1 : s + 1]);
    }
    rk4::finish(y, k_[0], k_[1], h);
  }

  static constexpr int evaluations_per_step = 4;
  static constexpr int order = 4;

 private:
  Eigen::VectorXd k_[3], tmp_;
};

}  // namespace mbsflow
