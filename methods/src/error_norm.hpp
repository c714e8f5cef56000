#pragma once
// How the implicit methods measure an error against the tolerances, as Radau5 and CVODE
// do: weights w_i = atol_i + rtol_i |y_i| from scalar or per-component tolerances, and the
// weighted RMS norm sqrt(1/n sum (e_i / w_i)^2), so that a tolerance means the same for a
// system of 4 or of 40 000 equations and a component below its atol is controlled in
// absolute terms.
#include <Eigen/Core>
#include <cmath>

namespace mbsflow {

// Settings with rtol, atol (scalars) and rtols, atols (per component; empty: the scalar).
template <class Settings, class Magnitude>
Eigen::ArrayXd tolerance_weights(const Settings& s, const Magnitude& magnitude) {
  Eigen::ArrayXd w(magnitude.size());
  if (s.rtols.size() > 0)
    w = s.rtols.array() * magnitude;
  else
    w = s.rtol * magnitude;
  if (s.atols.size() > 0)
    w += s.atols.array();
  else
    w += s.atol;
  return w;
}

template <class E, class W>
double weighted_rms(const E& e, const W& w) {
  return std::sqrt((e.array() / w.array()).square().mean());
}

}  // namespace mbsflow
