#pragma once
// Collocation block methods (seed 001): an m-step s-point method computes u at the s
// points t0 + i tau, i = 1..s, of a block at once from u and f at the m points
// t0 - (m-1) tau .. t0 before it and f at the block points:
//
//   u_i = sum_{j=-(m-1)}^{0} q_ij u_j + tau (sum_{j=-(m-1)}^{0} d_ij f_j + sum_{j=1}^{s} g_ij f_j).
//
// The coefficients are generated in exact rational arithmetic from exactness on
// polynomials (order conditions below); the doubles used by the solvers are rounded from
// the exact values.
//
// Equidistant one-step blocks are A-stable with R(infinity) = 0 for s <= 2 only (the
// stability table of docs/methods.md), so the stiff default is the other node family:
// one-step blocks whose points are the right Radau points t0 + c_i tau of one block of
// length tau (Radau IIA collocation, order 2s - 1, L-stable for every s). Their s- and
// (s+1)-point blocks cover the same interval and share its end point, where the step
// control compares them. Radau points are irrational from s = 3 on: that family's
// coefficients are computed in long double and carry no exact text.
#include "mbsflow/error.hpp"
#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

#include "mbsflow/methods/stability.hpp"

namespace mbsflow {

enum class BlockNodes { equidistant, radau };
const char* to_string(BlockNodes n);

struct BlockMethodSpec {
  int m = 1;      // steps (points before the block, the last one is the block start)
  int s = 2;      // points in the block
  int order = 0;  // 0: the maximal order; else a lower order q >= 1 (equidistant only)
  BlockNodes nodes = BlockNodes::equidistant;
  int maximal_order() const { return nodes == BlockNodes::radau ? 2 * s - 1 : 2 * m + s - 1; }
  int effective_order() const { return order > 0 ? order : maximal_order(); }
};
// The stiff default of the colloc method: Radau points, s = 3 (order 5, the (s+1)-point
// partner of order 7).
BlockMethodSpec default_block_method();
// "radau", "radau,S", "m,s" or "m,s,order" (equidistant); empty: the default. InputError otherwise.
BlockMethodSpec parse_block_method(const std::string& text);
std::string describe_block_method(const BlockMethodSpec& spec);
// The (s+1)-point block the step control runs beside an s-point one: same steps and
// nodes, order + 1 (or its maximal order).
BlockMethodSpec step_control_partner(const BlockMethodSpec& spec);  // e.g. "radau s = 3" or "m = 2, s = 3, order 4"

// Where the free coefficients of a lower-order method go. A method of order q needs
// q + 1 of the 2m + s coefficients of a row; the other 2m + s - 1 - q are set to zero in
// this order: first the u-coefficients of the oldest points (j = -(m-1), ..., -1: the
// method becomes of Adams type, whose only u is u_0, so its u-part has the single root 1
// and it is zero-stable for every m and s), then the f-coefficients of the oldest points
// (j = -(m-1), ..., 0: for m = 1 dropping f_0 turns the Lobatto-type collocation into a
// Radau-type one, whose stability function vanishes at infinity). Each row keeps the
// same set, so the method is one collocation polynomial of degree q through the kept data.
struct BlockCoefficients {
  BlockMethodSpec spec;
  int order = 0;                    // exact order of every row
  Eigen::MatrixXd q, d, g;          // s x m, s x m, s x s (column j <-> point j-(m-1), resp. j+1)
  // Where the block points lie, in steps tau after the block start: 1..s (equidistant) or
  // the Radau points c_i (the block ends at 1).
  Eigen::VectorXd positions;
  double span() const { return positions(positions.size() - 1); }
  bool exact = true;                                   // false: no exact text (Radau points)
  std::vector<std::string> q_exact, d_exact, g_exact;  // row-major, as "p/q" (decimal when !exact)
  std::vector<bool> keep_u, keep_f;  // m and m + s flags: which data the method uses
};

// Throws InputError for m < 1, s < 1, order outside 1..2m+s-1, or an order
// that the kept data cannot reach.
BlockCoefficients generate_block_method(const BlockMethodSpec& spec);

// Weights of the method's interpolation polynomial at t0 + theta tau (theta real, any
// value): u(theta) = sum wu_j u_j + tau (sum wd_j f_j + sum wg_j f_{j+1}); at theta = i
// they are row i of the method. This is the dense output inside a block.
struct DenseWeights {
  Eigen::VectorXd wu, wd, wg;  // m, m, s
};
DenseWeights dense_output_weights(const BlockCoefficients& method, double theta);

// One-step methods (m = 1) on y' = lambda y, z = lambda tau: u_s = R(z) u_0 with
// R = P / Q. Coefficients from the constant term up, exact and rounded.
struct StabilityFunction {
  std::vector<std::string> numerator_exact, denominator_exact;
  Eigen::VectorXd numerator, denominator;
  double infinity = 0;  // |R(z)| as |z| -> infinity
  std::complex<double> operator()(std::complex<double> z) const;
  double at_infinity() const { return infinity; }
};
StabilityFunction stability_function(const BlockCoefficients& method);

// A-stability of a one-step block method (stability.hpp; the poles are 1/mu for the
// eigenvalues mu of g).
StabilityReport check_a_stability(const BlockCoefficients& method);

// Zero-stability (root condition) of a multistep block method: with f = 0 a step maps the
// window of m past values to the next one by a fixed m x m matrix; the method is
// zero-stable when its eigenvalues lie in the closed unit disc and those on the circle
// are simple; strongly so when only the principal one (1) is on the circle. One-step
// methods are trivially (strongly) zero-stable.
struct ZeroStability {
  bool zero_stable = true, strongly = true;
  double parasitic_radius = 0;  // largest |eigenvalue| other than the principal 1
};
ZeroStability check_zero_stability(const BlockCoefficients& method);

// Order-condition residuals in exact arithmetic: the largest |residual| over all rows and
// l = 0..order as a string ("0" when they all hold exactly; in doubles, "%.3g", for a
// method without exact coefficients). For tests and --describe.
std::string order_condition_residual(const BlockCoefficients& method);

}  // namespace mbsflow
