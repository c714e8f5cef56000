#pragma once
// Real or complex numbers in checkpoints: as doubles, a complex one as two.
#include <Eigen/Core>
#include <cstring>
#include <vector>

#include "mbsflow/methods/state_archive.hpp"

namespace mbsflow {

template <class Scalar>
Eigen::VectorXd as_reals(const Scalar* v, Eigen::Index n) {
  constexpr int k = sizeof(Scalar) / sizeof(double);
  Eigen::VectorXd out(n * k);
  if (n > 0) std::memcpy(out.data(), v, static_cast<std::size_t>(n) * sizeof(Scalar));
  return out;
}

template <class Scalar>
std::vector<Scalar> from_reals(const Eigen::VectorXd& r, StateReader& in) {
  constexpr int k = sizeof(Scalar) / sizeof(double);
  if (r.size() % k != 0) in.fail("a complex vector of odd length");
  std::vector<Scalar> out(static_cast<std::size_t>(r.size() / k));
  if (!out.empty()) std::memcpy(static_cast<void*>(out.data()), r.data(), out.size() * sizeof(Scalar));
  return out;
}

}  // namespace mbsflow
