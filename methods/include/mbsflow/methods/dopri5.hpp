#pragma once
// Dormand-Prince 5(4) with error control (PI step-size controller) and Shampine's
// fourth-order dense output, after Hairer, Norsett & Wanner, Solving ODE I, II.4-5.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "mbsflow/methods/ode_system.hpp"
#include "mbsflow/methods/state_archive.hpp"

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

// The arithmetic of DOPRI5, element by element, shared by the stepper below and the
// partitioned executor, so that both compute the same numbers to the bit. k(j) gives the
// j-th stage derivative (j = 0..6), as a vector or a segment of one.
namespace dopri5 {

inline constexpr double c[7] = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
inline constexpr double a21 = 1.0 / 5;
inline constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
inline constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
inline constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
inline constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                        a65 = -5103.0 / 18656;
inline constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784, a76 = 11.0 / 84;
inline constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                        e6 = 22.0 / 525, e7 = -1.0 / 40;
inline constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                        d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                        d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

// Input of stage s = 1..6 (the one that gives k(s)); stage 6's input is the new solution.
template <class Y, class K, class Out>
void stage_input(int s, const Y& y, K k, double h, Out&& out) {
  switch (s) {
    case 1: out = y + h * (a21 * k(0)); break;
    case 2: out = y + h * (a31 * k(0) + a32 * k(1)); break;
    case 3: out = y + h * (a41 * k(0) + a42 * k(1) + a43 * k(2)); break;
    case 4: out = y + h * (a51 * k(0) + a52 * k(1) + a53 * k(2) + a54 * k(3)); break;
    case 5: out = y + h * (a61 * k(0) + a62 * k(1) + a63 * k(2) + a64 * k(3) + a65 * k(4)); break;
    default: out = y + h * (a71 * k(0) + a73 * k(2) + a74 * k(3) + a75 * k(4) + a76 * k(5)); break;
  }
}

// Squares of the scaled local error estimate, element by element.
template <class Y, class K, class Out>
void error_squares(const Y& y, const Y& y_new, K k, double h, double atol, double rtol, Out&& out) {
  out = ((h * (e1 * k(0) + e3 * k(2) + e4 * k(3) + e5 * k(4) + e6 * k(5) + e7 * k(6))).array() /
         (atol + rtol * y.array().abs().max(y_new.array().abs())))
            .square()
            .matrix();
}

// Sum in element order: a partitioned run adds the same terms in the same order.
template <class V>
double ordered_sum(const V& v) {
  double s = 0.0;
  for (Eigen::Index i = 0; i < v.size(); ++i) s += v[i];
  return s;
}

// Dense output coefficients of an accepted step (r[0..4]) and their evaluation.
template <class Y, class K, class R>
void dense_setup(const Y& y, const Y& y_new, K k, double h, R r) {
  r(0) = y;
  r(1) = y_new - y;
  r(2) = h * k(0) - r(1);
  r(3) = r(1) - h * k(6) - r(2);
  r(4) = h * (d1 * k(0) + d3 * k(2) + d4 * k(3) + d5 * k(4) + d6 * k(5) + d7 * k(6));
}
template <class R, class Out>
void dense_eval(R r, double theta, Out&& out) {
  const double th1 = 1.0 - theta;
  out = r(0) + theta * (r(1) + th1 * (r(2) + theta * (r(3) + th1 * r(4))));
}

// The PI step-size controller: accept or reject a step of size h with scaled error err,
// and propose the next step.
class Controller {
 public:
  explicit Controller(const Dopri5Settings& s) : s_(s) {}
  struct Decision {
    bool accept;
    double h;  // next step to try
  };
  Decision decide(double err, double h) {
    if (!std::isfinite(err)) {
      rejected_before_ = true;
      return {false, h * s_.facmin};
    }
    const double expo = 0.2 - 0.75 * s_.beta;
    const double fac = std::pow(std::max(err, 1e-10), expo) * std::pow(err_old_, -s_.beta) / s_.safety;
    if (err <= 1.0) {
      err_old_ = std::max(err, 1e-4);
      double h_new = h / std::clamp(fac, 1.0 / s_.facmax, 1.0 / s_.facmin);
      if (rejected_before_) h_new = std::min(h_new, h);
      rejected_before_ = false;
      return {true, h_new};
    }
    rejected_before_ = true;
    return {false, h / std::min(1.0 / s_.facmin, fac)};
  }
  double h_min(double t) const {
    return s_.h_min > 0.0 ? s_.h_min : 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
  }
  // One accepted step from t, trying h first: attempt() computes the stages for step h and
  // returns the error norm; each rejected attempt is counted in `rejected`. On return
  // `taken` is the accepted step and h the next one to try; false when h fell below
  // h_min(t) (the caller reports it). Dopri5::step and the tightly coupled run, whose
  // stages are spread over submodels, take their steps through this one loop.
  template <class Attempt>
  bool accepted_step(double t, double& h, double& taken, long& rejected, Attempt attempt) {
    while (true) {
      if (h < h_min(t)) return false;
      const Decision d = decide(attempt(), h);
      if (d.accept) {
        taken = h;
        h = d.h;
        return true;
      }
      ++rejected;
      h = d.h;
    }
  }

  // What the controller carries from step to step (checkpoints).
  void save(StateWriter& out) const {
    out.real(err_old_);
    out.flag(rejected_before_);
  }
  void restore(StateReader& in) {
    err_old_ = in.real();
    rejected_before_ = in.flag();
  }

 private:
  Dopri5Settings s_;
  double err_old_ = 1e-4;
  bool rejected_before_ = false;
};

}  // namespace dopri5

// The message of a run whose DOPRI5 step size fell below its minimum.
std::string step_collapsed_message(double h, double t, double rtol);

class Dopri5 {
 public:
  Dopri5(Eigen::Index n, Dopri5Settings s = {}) : s_(s), control_(s), tmp_(n), sq_(n) {
    for (auto& v : k_) v.resize(n);
    for (auto& v : r_) v.resize(n);
  }

  const Dopri5Stats& stats() const { return stats_; }
  const Dopri5Settings& settings() const { return s_; }

  // Call after changing y between steps (the stored f(t, y) is then stale).
  void invalidate() { fsal_ = false; }

  // A starting step from the system's scales (Hairer's algorithm, order 5).
  template <OdeSystem S>
  double initial_step(S& sys, double t, const Eigen::VectorXd& y) {
    sys.rhs(t, y, k_[0]);
    ++stats_.evaluations;
    fsal_ = true;
    const Eigen::VectorXd sc = s_.atol + s_.rtol * y.array().abs();
    const double d0 = rms(y, sc), d1 = rms(k_[0], sc);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    tmp_ = y + h0 * k_[0];
    sys.rhs(t + h0, tmp_, k_[1]);
    ++stats_.evaluations;
    const double d2 = rms(k_[1] - k_[0], sc) / h0;
    const double m = std::max(d1, d2);
    const double h1 = m <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / m, 1.0 / 5.0);
    return std::min(100.0 * h0, h1);
  }

  // Takes one accepted step from (t, y), starting with step h; on return y holds the
  // solution at t + taken, h the proposed next step. Returns false when the step fell
  // below h_min (the caller reports it).
  template <OdeSystem S>
  bool step(S& sys, double t, double& h, Eigen::VectorXd& y, double& taken) {
    if (!fsal_) {
      sys.rhs(t, y, k_[0]);
      ++stats_.evaluations;
      fsal_ = true;
    }
    auto k = [this](int j) -> const Eigen::VectorXd& { return k_[j]; };
    const bool ok = control_.accepted_step(t, h, taken, stats_.rejected, [&] {
      for (int s = 1; s < 7; ++s) {
        dopri5::stage_input(s, y, k, h, tmp_);
        sys.rhs(t + dopri5::c[s] * h, tmp_, k_[s]);
      }
      stats_.evaluations += 6;
      dopri5::error_squares(y, tmp_, k, h, s_.atol, s_.rtol, sq_);
      return std::sqrt(dopri5::ordered_sum(sq_) / static_cast<double>(sq_.size()));
    });
    if (!ok) return false;
    dopri5::dense_setup(y, tmp_, k, taken, [this](int i) -> Eigen::VectorXd& { return r_[i]; });
    t_old_ = t;
    h_old_ = taken;
    y = tmp_;
    k_[0].swap(k_[6]);  // first same as last
    ++stats_.accepted;
    return true;
  }

  // Dense output of the last accepted step at time t in [t_old, t_old + h_old].
  void dense(double t, Eigen::VectorXd& out) const {
    dopri5::dense_eval([this](int i) -> const Eigen::VectorXd& { return r_[i]; }, (t - t_old_) / h_old_, out);
  }

  static constexpr int order = 5;

  // Checkpoints: the controller's memory, the counters and the kept f(t, y); not the dense
  // output of the last step (five states' worth), which the next step makes anew.
  void save(StateWriter& out) const {
    control_.save(out);
    for (long v : {stats_.accepted, stats_.rejected, stats_.evaluations}) out.integer(v);
    out.flag(fsal_);
    if (fsal_) out.vector(k_[0]);
  }
  void restore(StateReader& in) {
    control_.restore(in);
    for (long* v : {&stats_.accepted, &stats_.rejected, &stats_.evaluations}) *v = in.integer(0, INT64_MAX);
    fsal_ = in.flag();
    if (fsal_) k_[0] = in.vector(tmp_.size());
  }

 private:
  static double rms(const Eigen::VectorXd& v, const Eigen::VectorXd& sc) {
    return std::sqrt((v.array() / sc.array()).square().mean());
  }

  Dopri5Settings s_;
  dopri5::Controller control_;
  Dopri5Stats stats_;
  bool fsal_ = false;
  double t_old_ = 0.0, h_old_ = 1.0;
  Eigen::VectorXd k_[7], r_[5], tmp_, sq_;
};

}  // namespace mbsflow
