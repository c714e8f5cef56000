#pragma once
// The step size controller of the implicit integrators, as Radau5's (Hairer & Wanner IV.8):
// the classical factor safety * err^(-1/k) with a safety that shrinks when Newton needed
// many iterations, and after an accepted step Gustafsson's predictive factor
//   (h / h_acc) * safety * (err_acc / err^2)^(1/k),
// which uses the last accepted step's error to see the error's trend; the smaller of the
// two is taken, so a step whose error grows fast from one step to the next does not grow
// into a rejection. k = order of the error estimate + 1.
#include <algorithm>
#include <cmath>

namespace mbsflow {

struct StepController {
  double safety = 0.9, facmin = 0.2, facmax = 4.0;
  int max_iterations = 7;  // of the Newton iteration (Radau5's nit)
  bool predictive = true;
  // The last accepted step and its error (max(err, 1e-2), as Radau5).
  double h_accepted = 0, err_accepted = 0;
  // Accepted steps that may still grow by 1.2 at most. The step the error allows can be
  // beyond where the Newton iteration converges (a nonlinear model far from its last
  // Jacobian, as A05's rotating stiff couplers): after an iteration with a fresh Jacobian
  // failed and the step was halved, it grows slowly for a while instead of growing back
  // into the same failure.
  int slow_growth = 0;

  void after_halving() { slow_growth = 10; }
  // An accepted step's factor, held to 1.2 while the slow growth lasts.
  double limit_growth(double fac) {
    if (slow_growth <= 0) return fac;
    --slow_growth;
    return std::min(fac, 1.2);
  }

  // Radau5: safe * (1 + 2 nit) / (newt + 2 nit): 0.9 after one iteration, 0.64 after seven.
  double newton_safety(int iterations) const {
    return std::min(safety, safety * (1 + 2 * max_iterations) / (std::max(iterations, 1) + 2 * max_iterations));
  }

  // The factor h_new / h after a step with scaled error err (<= 1: accepted) and exponent
  // 1/k, the Newton iteration having taken `iterations`.
  double factor(double h, double err, double exponent, int iterations, bool accepted) {
    const double safe = newton_safety(iterations);
    auto clamp = [&](double f) { return std::clamp(f, facmin, facmax); };
    double fac = err == 0 ? facmax : clamp(safe * std::pow(err, -exponent));
    if (!accepted) return fac;
    if (predictive && h_accepted > 0 && err > 0)
      fac = std::min(fac, clamp((h / h_accepted) * safe * std::pow(err_accepted / (err * err), exponent)));
    h_accepted = h;
    err_accepted = std::max(1e-2, err);
    return fac;
  }
};

}  // namespace mbsflow
