#pragma once
// Dormand-Prince 5(4) with error control (PI step-size controller) and Shampine's
// fourth-order dense output, after Hairer, Norsett & Wanner, Solving ODE I, II.4-5.
#include <algorithm>
#include <cmath>
#include <limits>

#include "mbsflow/methods/ode_system.hpp"

namespace mbsflow {

struct Dopri5Settings {
  double rtol = 1e-6;
  double atol = 1e-8;
  double safety = 0.9;
  double facmin = 0.2;   // smallest step ratio
  double facmax = 10.0;  // largest step ratio
  double beta = 0.04;    // PI controller (Gustafsson); 0 gives the classic I controller
  double h_min = 0.0;    // 0: about 1e-14 |t|
};

struct Dopri5Stats {
  long accepted = 0;
  long rejected = 0;
  long evaluations = 0;
};

class Dopri5 {
 public:
  Dopri5(Eigen::Index n, Dopri5Settings s = {})
      : s_(s), k1_(n), k2_(n), k3_(n), k4_(n), k5_(n), k6_(n), k7_(n), tmp_(n), err_(n),
        r1_(n), r2_(n), r3_(n), r4_(n), r5_(n) {}

  const Dopri5Stats& stats() const { return stats_; }
  const Dopri5Settings& settings() const { return s_; }

  // Call after changing y between steps (the stored f(t, y) is then stale).
  void invalidate() { fsal_ = false; }

  // A starting step from the system's scales (Hairer's algorithm, order 5).
  template <OdeSystem S>
  double initial_step(S& sys, double t, const Eigen::VectorXd& y) {
    sys.rhs(t, y, k1_);
    ++stats_.evaluations;
    fsal_ = true;
    const Eigen::VectorXd sc = s_.atol + s_.rtol * y.array().abs();
    const double d0 = rms(y, sc), d1 = rms(k1_, sc);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    tmp_ = y + h0 * k1_;
    sys.rhs(t + h0, tmp_, k2_);
    ++stats_.evaluations;
    const double d2 = rms(k2_ - k1_, sc) / h0;
    const double m = std::max(d1, d2);
    const double h1 = m <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / m, 1.0 / 5.0);
    return std::min(100.0 * h0, h1);
  }

  // Takes one accepted step from (t, y), starting with step h; on return y holds the
  // solution at t + taken, h the proposed next step. Throws nothing: returns false
  // when the step fell below h_min (the caller reports it).
  template <OdeSystem S>
  bool step(S& sys, double t, double& h, Eigen::VectorXd& y, double& taken) {
    if (!fsal_) {
      sys.rhs(t, y, k1_);
      ++stats_.evaluations;
      fsal_ = true;
    }
    const double h_min = s_.h_min > 0.0 ? s_.h_min : 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
    bool rejected_before = false;
    while (true) {
      if (h < h_min) return false;
      stages(sys, t, h, y);
      // Scaled error norm.
      err_ = h * (e1 * k1_ + e3 * k3_ + e4 * k4_ + e5 * k5_ + e6 * k6_ + e7 * k7_);
      const Eigen::ArrayXd sc = s_.atol + s_.rtol * y.array().abs().max(tmp_.array().abs());
      const double err = std::sqrt((err_.array() / sc).square().mean());
      if (!std::isfinite(err)) {
        h *= s_.facmin;
        ++stats_.rejected;
        rejected_before = true;
        continue;
      }
      const double expo = 0.2 - 0.75 * s_.beta;
      double fac = std::pow(std::max(err, 1e-10), expo) * std::pow(err_old_, -s_.beta) / s_.safety;
      if (err <= 1.0) {
        // Accepted: set up the dense output on [t, t + h], then move on.
        r1_ = y;
        r2_ = tmp_ - y;
        r3_ = h * k1_ - r2_;
        r4_ = r2_ - h * k7_ - r3_;
        r5_ = h * (d1 * k1_ + d3 * k3_ + d4 * k4_ + d5 * k5_ + d6 * k6_ + d7 * k7_);
        t_old_ = t;
        h_old_ = h;
        y = tmp_;
        k1_.swap(k7_);  // first same as last
        err_old_ = std::max(err, 1e-4);
        ++stats_.accepted;
        taken = h;
        fac = std::clamp(fac, 1.0 / s_.facmax, 1.0 / s_.facmin);
        double h_new = h / fac;
        if (rejected_before) h_new = std::min(h_new, h);
        h = h_new;
        return true;
      }
      ++stats_.rejected;
      rejected_before = true;
      h /= std::min(1.0 / s_.facmin, fac);
    }
  }

  // Dense output of the last accepted step at time t in [t_old, t_old + h_old].
  void dense(double t, Eigen::VectorXd& out) const {
    const double th = (t - t_old_) / h_old_, th1 = 1.0 - th;
    out = r1_ + th * (r2_ + th1 * (r3_ + th * (r4_ + th1 * r5_)));
  }

  static constexpr int order = 5;

 private:
  template <OdeSystem S>
  void stages(S& sys, double t, double h, const Eigen::VectorXd& y) {
    tmp_ = y + h * (a21 * k1_);
    sys.rhs(t + c2 * h, tmp_, k2_);
    tmp_ = y + h * (a31 * k1_ + a32 * k2_);
    sys.rhs(t + c3 * h, tmp_, k3_);
    tmp_ = y + h * (a41 * k1_ + a42 * k2_ + a43 * k3_);
    sys.rhs(t + c4 * h, tmp_, k4_);
    tmp_ = y + h * (a51 * k1_ + a52 * k2_ + a53 * k3_ + a54 * k4_);
    sys.rhs(t + c5 * h, tmp_, k5_);
    tmp_ = y + h * (a61 * k1_ + a62 * k2_ + a63 * k3_ + a64 * k4_ + a65 * k5_);
    sys.rhs(t + h, tmp_, k6_);
    tmp_ = y + h * (a71 * k1_ + a73 * k3_ + a74 * k4_ + a75 * k5_ + a76 * k6_);
    sys.rhs(t + h, tmp_, k7_);
    stats_.evaluations += 6;
  }

  static double rms(const Eigen::VectorXd& v, const Eigen::VectorXd& sc) {
    return std::sqrt((v.array() / sc.array()).square().mean());
  }

  static constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  static constexpr double a21 = 1.0 / 5;
  static constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
  static constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  static constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
  static constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                          a65 = -5103.0 / 18656;
  static constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784,
                          a76 = 11.0 / 84;
  static constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                          e6 = 22.0 / 525, e7 = -1.0 / 40;
  static constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                          d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                          d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

  Dopri5Settings s_;
  Dopri5Stats stats_;
  bool fsal_ = false;
  double err_old_ = 1e-4;
  double t_old_ = 0.0, h_old_ = 1.0;
  Eigen::VectorXd k1_, k2_, k3_, k4_, k5_, k6_, k7_, tmp_, err_, r1_, r2_, r3_, r4_, r5_;
};

}  // namespace mbsflow
