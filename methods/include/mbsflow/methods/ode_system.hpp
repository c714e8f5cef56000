#pragma once
// What a method needs from a system: its dimension and y' = f(t, y).
#include <Eigen/Core>
#include <concepts>

namespace mbsflow {

template <class S>
concept OdeSystem = requires(S& s, double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
  { s.dimension() } -> std::convertible_to<Eigen::Index>;
  s.rhs(t, y, dydt);
};

// A system from a callable, for tests and for user systems in the library API.
template <class F>
struct FunctionSystem {
  Eigen::Index n;
  F f;
  Eigen::Index dimension() const { return n; }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { f(t, y, dydt); }
};
template <class F>
FunctionSystem<F> make_system(Eigen::Index n, F f) {
  return {n, std::move(f)};
}

}  // namespace mbsflow
