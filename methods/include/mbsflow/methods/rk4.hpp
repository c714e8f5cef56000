#pragma once
// Classic fourth-order Runge-Kutta with a fixed step.
#include "mbsflow/methods/ode_system.hpp"

namespace mbsflow {

class Rk4 {
 public:
  explicit Rk4(Eigen::Index n) : k1_(n), k2_(n), k3_(n), k4_(n), tmp_(n) {}

  // Advances y from t to t + h. Four evaluations of f.
  template <OdeSystem S>
  void step(S& sys, double t, double h, Eigen::VectorXd& y) {
    const double h2 = 0.5 * h;
    sys.rhs(t, y, k1_);
    tmp_ = y + h2 * k1_;
    sys.rhs(t + h2, tmp_, k2_);
    tmp_ = y + h2 * k2_;
    sys.rhs(t + h2, tmp_, k3_);
    tmp_ = y + h * k3_;
    sys.rhs(t + h, tmp_, k4_);
    y += (h / 6.0) * (k1_ + 2.0 * (k2_ + k3_) + k4_);
  }

  static constexpr int evaluations_per_step = 4;
  static constexpr int order = 4;

 private:
  Eigen::VectorXd k1_, k2_, k3_, k4_, tmp_;
};

}  // namespace mbsflow
