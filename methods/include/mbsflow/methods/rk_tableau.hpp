#pragma once
// Implicit Runge-Kutta tableaux and their triangular splitting (seed 004):
//
//   x_{n+1} = x_n + tau sum_i b_i K_i,   K_i = f(t_n + c_i tau, x_n + tau sum_j a_ij K_j).
//
// The implicit part of A is factorised once, A = L D U (L, U unit triangular, D
// diagonal), giving the triangular T_L = L D and T_U = U with A = T_L T_U, and the
// diagonal approximation D. These are the matrices T of the iterations in
// tirk_integrator.hpp.
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

#include "mbsflow/methods/stability.hpp"

namespace mbsflow {

struct RkTableau {
  std::string name;    // radau2, radau3, radau5, gauss2, gauss3, lobatto3c, block1..block6
  std::string family;  // in words
  int order = 0;
  Eigen::MatrixXd a;   // s x s
  Eigen::VectorXd b, c;
  // Stage 1 is explicit (zero first row, c_1 = 0: K_1 = f(t_n, x_n)), as in the one-step
  // block methods; the splitting then covers stages 2..s.
  bool explicit_first = false;
  int stages() const { return static_cast<int>(b.size()); }
  int first_implicit() const { return explicit_first ? 1 : 0; }
  int implicit_stages() const { return stages() - first_implicit(); }
  Eigen::MatrixXd implicit_block() const;  // rows and columns of the implicit stages
};

// The LDU factorisation of the implicit block (no pivoting: the stage order is the order
// in which the triangular iteration visits the stages).
struct TriangularSplitting {
  Eigen::MatrixXd l, u;      // unit lower / unit upper
  Eigen::VectorXd d;         // pivots
  Eigen::MatrixXd t_lower;   // T_L = L D: lower triangular with D on the diagonal
  Eigen::MatrixXd t_upper;   // T_U = U
  Eigen::MatrixXd diagonal;  // D as a matrix
  double reconstruction_error = 0;  // max |T_L T_U - A|
  // The seed writes T_L = L - I + D; with the unit L of A = L D U that product misses A
  // by this much (it equals L D only where D = I). Reported, not used.
  double seed_formula_error = 0;
};

// Throws InputError when a leading minor vanishes (no LDU without pivoting).
TriangularSplitting ldu_splitting(const Eigen::MatrixXd& a);

// An embedded solution for step control, one order lower than the stage values can
// carry: x^_{n+1} = x_n + tau (gamma f(t_n, x_n) + sum_i bhat_i K_i), of order `order`.
// gamma > 0 is one of the pivots d_i, so that the stiff filter (I - tau gamma J)^-1
// reuses a factorisation of the Newton-type iterations (Hairer & Wanner, IV.8).
struct EmbeddedFormula {
  double gamma = 0;
  Eigen::VectorXd bhat;
  int order = 0;
};
EmbeddedFormula embedded_formula(const RkTableau& t, const TriangularSplitting& split);  // gamma = max d_i
EmbeddedFormula embedded_formula(const RkTableau& t, double gamma);
// The largest real eigenvalue of A's implicit block, 0 if it has none (the full Newton
// iteration's estimate filters through its system).
double largest_real_eigenvalue(const RkTableau& t);

// Radau IIA with s stages (1..12): collocation at the right Radau points, order 2s - 1,
// L-stable. InputError outside 1..12.
RkTableau radau_iia(int s);

// The stability function R(z) = 1 + z b^T (I - z A)^-1 1 and its report (stability.hpp).
std::complex<double> stability_value(const RkTableau& t, std::complex<double> z);
StabilityReport check_a_stability(const RkTableau& t);
// Stiffly accurate: the last row of A is b^T (and c_s = 1), so the step's end is the last
// stage and stiff components are as damped as the stages are.
bool stiffly_accurate(const RkTableau& t);

// By name ("radau1".."radau12" for every stage count); throws InputError with the list of names otherwise.
RkTableau rk_tableau(const std::string& name);
std::vector<std::string> rk_tableau_names();

// Largest |sum_i b_i c_i^(k-1) - 1/k| and |sum_j a_ij c_j^(k-1) - c_i^k / k| over the
// simplifying conditions B(order) and C(stage_order): a check of the coefficients.
double quadrature_residual(const RkTableau& t, int order);
double stage_order_residual(const RkTableau& t, int stage_order);

}  // namespace mbsflow
