#pragma once
// One block of a collocation block method as a subgraph of a oneTBB flow graph: the
// implicit equations U_i = B_i + tau sum_l g_il f(t_i, U_l), i = 1..k, iterated until
// converged. Every block point is a node (and, for large systems, each slice of
// equations of a point); the layers of one iteration are:
//
//   prepare(slice) -> f(point, slice) -> gate -> [Newton: residual(slice) -> solve(e)] -> update(slice) -> f ...
//
// The simplified Newton iteration diagonalises g = T diag(mu) T^-1 once, so its linear
// system splits into one system (I - tau mu_e J) w_e = z_e per eigenvalue (one per complex
// pair), each a node of its own. Every node writes its own rows only and the norms are
// maxima, so the numbers do not depend on the thread count or the order nodes run in.
#include <oneapi/tbb/flow_graph.h>

#include <complex>
#include <memory>
#include <vector>

#include "annotated_node.hpp"
#include "convergence_monitor.hpp"
#include "eigen_split.hpp"
#include "mbsflow/methods/block_integrator.hpp"

namespace mbsflow {

class BlockSolve {
 public:
  BlockSolve(const BlockCoefficients& method, const OdeProblem& problem, const BlockSettings& settings,
             Eigen::Index slice_size);
  BlockSolve(const BlockSolve&) = delete;
  BlockSolve& operator=(const BlockSolve&) = delete;

  const BlockCoefficients& method() const { return method_; }
  int points() const { return method_.spec.s; }

  // The linear systems of the Newton iteration: one per real eigenvalue or complex pair.
  int systems() const { return split_ ? split_->systems() : 0; }
  // Factorising I - tau mu_e J for every system, each a node of the graph: set up, start
  // (then g.wait_for_all() and finished()), and whether all matrices were regular.
  void request_factorization(const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind);
  void start_factorization();
  bool factorization_ok() const;

  // The data of one attempt (read by the nodes; must outlive the run).
  void setup(double t0, double tau, const std::vector<Eigen::VectorXd>& past_u, const std::vector<Eigen::VectorXd>& past_f,
             const Eigen::VectorXd& scale);
  void build(tbb::flow::graph& g);
  void start();     // call before g.wait_for_all()
  void finished();  // call after it
  // The same iteration (or factorisations) on the calling thread, layer by layer in the
  // graph's order: for systems too small for the graph's scheduling to pay. The same
  // numbers, since every node writes its own rows and the norms are maxima.
  void run_inline();
  void factorize_inline();

  // Checkpoints: what carries over from one block to the next (the iteration's eta and
  // the Newton matrices' factors; `pattern`: a Jacobian of the run's pattern).
  void save(StateWriter& out) const;
  void restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern);

  // After the run.
  std::vector<Eigen::VectorXd> u, f;  // at t0 + i tau, i = 1..k
  int iterations = 0;
  bool failed = false;
  long evaluations = 0;

 private:
  using Node = ContinueNode;
  using Start = tbb::flow::broadcast_node<tbb::flow::continue_msg>;

  Eigen::Index slices() const { return (n_ + slice_ - 1) / slice_; }
  Eigen::Index slice_begin(Eigen::Index r) const { return r * slice_; }
  Eigen::Index slice_length(Eigen::Index r) const { return std::min(slice_, n_ - r * slice_); }
  void factorize(int system);
  void prepare(Eigen::Index r);
  void evaluate(int i, Eigen::Index first_slice, Eigen::Index slice_count);
  bool gate();  // true: iterate again
  void residual(Eigen::Index r);
  void solve(int e);
  void update(Eigen::Index r);
  void functional_update(Eigen::Index r);

  BlockCoefficients method_;
  const OdeProblem& problem_;
  BlockIteration kind_;
  ConvergenceMonitor monitor_;
  Eigen::Index n_, slice_;
  std::unique_ptr<EigenSplit> split_;  // Newton only
  std::vector<Eigen::VectorXd> b_, r_;
  std::vector<double> slice_norm_;
  std::vector<char> slice_at_roundoff_;
  std::vector<char> f_not_finite_;  // per point and slice: the last f had a NaN or infinity  // the last correction was within rounding of the iterate
  // The attempt.
  double t0_ = 0, tau_ = 0;
  const std::vector<Eigen::VectorXd>* past_u_ = nullptr;
  const std::vector<Eigen::VectorXd>* past_f_ = nullptr;
  const Eigen::VectorXd* scale_ = nullptr;
  // The subgraph.
  std::unique_ptr<Start> start_, evaluate_start_, correct_start_, factor_start_;
  const Eigen::SparseMatrix<double>* factor_jac_ = nullptr;
  double factor_tau_ = 0;
  LinearSolverKind factor_kind_ = LinearSolverKind::automatic;
  std::vector<char> factor_failed_;
  std::vector<std::unique_ptr<Node>> nodes_;
  long token_ = 0;  // ThreadSanitizer's view of the node order (tsan_annotations.hpp)
};

}  // namespace mbsflow
