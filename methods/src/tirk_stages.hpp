#pragma once
// One iteration of a triangularised Runge-Kutta method as a oneTBB flow graph (the
// formulas are in tirk_integrator.hpp). For implicit stage i and slice r of equations:
//
//   assemble(i, r): G_i = x_n + tau sum_j a_ij F_j^old + tau sum_{j<i} t_ij (F_j^new - F_j^old)
//     functional: Y_i = G_i, then (inner substitutions) Y_i = G_i + tau t_ii (f(Y_i) - F_i^old)
//     Newton:     solve(i): (I - tau t_ii J) dY = G_i - Y_i^old, Y_i = Y_i^old + dY
//   evaluate(i, r): F_i^new = f(t_n + c_i tau, Y_i)
//
// The full simplified Newton iteration ("newton", as Radau5) has no splitting: all stages
// evaluate f at the current iterate at once, then the residuals
// R_i = Y_i - x_n - tau sum_j a_ij F_j of all stages go through the eigenvector transform
// of A (eigen_split.hpp), one node per slice; every real eigenvalue and complex pair of A
// solves its system in a node of its own; the corrections come back per slice. So it has
// no predictor evaluations, and the converged iterate is not evaluated (as in Radau5): the
// driver takes the K_j it needs from the stage values (A^-1 Z / tau), which saves an
// iteration's evaluations per step.
//
// With the triangular T, assemble(i, r) waits for evaluate(j, r) of the stages j < i with
// t_ij != 0 (a pipelined DAG: slices of stage i start as soon as the same slices of the
// earlier stages are done); with the diagonal T or Jacobi all stages start together.
// Every node writes its own rows only and the driver reduces in a fixed order, so the
// numbers do not depend on the thread count.
#include <oneapi/tbb/flow_graph.h>

#include <memory>
#include <vector>

#include "convergence_monitor.hpp"
#include "eigen_split.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

namespace mbsflow {

class TirkStages {
 public:
  // filter_gamma: the value gamma of the error estimate's stiff filter (I - tau gamma J)^-1
  // (one of the diagonal values of T; for the full Newton iteration a real eigenvalue of
  // A, or a factorisation of its own is added).
  TirkStages(const RkTableau& tableau, const Eigen::MatrixXd& t, TirkIteration kind, int inner_iterations,
             const OdeProblem& problem, Eigen::Index slice_size, double filter_gamma);
  TirkStages(const TirkStages&) = delete;
  TirkStages& operator=(const TirkStages&) = delete;

  void build(tbb::flow::graph& g);

  // Checkpoints: the factors of every linear system (the stage values are set anew by
  // every setup()); `pattern`: a Jacobian of the run's pattern.
  void save(StateWriter& out) const;
  void restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern);

  // Factorising I - tau t_ii J for every distinct t_ii (Newton-type iterations), one node
  // each: request, start (then wait_for_all and finished()), check.
  void request_factorization(const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind);
  void start_factorization();
  void finished_factorization();
  bool factorization_ok() const;
  // Linear systems factorised per Jacobian and step size.
  int systems() const;
  // (I - tau gamma J)^-1 v with the factorisation of the diagonal value gamma (one of t_ii).
  void solve_with(double gamma, Eigen::VectorXd& v) const;

  // A step from (t, x, fx = f(t, x)): the predictor Y_i = guess[i] (default: the trivial
  // Y_i = x), F_i = fx; then start_predictor() (and wait_for_all, finished_predictor())
  // evaluates F_i = f(t_n + c_i tau, Y_i) for the stages with c_i != 0, so that the first
  // correction measures the iteration (the full Newton iteration: nothing, each of its
  // iterations evaluates its iterate first).
  void setup(double t, double tau, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, const Eigen::VectorXd& scale,
             const std::vector<Eigen::VectorXd>* guess = nullptr);
  void start_predictor();
  void finished_predictor();
  long predictor_evaluations() const;
  void start();     // one iteration; call g.wait_for_all() after it
  void finished();  // after wait_for_all: the new iterate becomes the current one
  // The same three jobs on the calling thread, the graph's node bodies in one of its
  // orders, instead of start_factorization(), start_predictor() and start() with
  // wait_for_all (finished_*() after each as before). Each node's numbers depend only on
  // what its predecessors wrote, so the results are the graph's bit for bit; what goes is
  // the dispatch of a task per node, which on a small system costs as much as the work.
  void factorize_here();
  void predict_here();
  void iterate_here();
  // After finished(): the scaled size of the last correction, whether it was at rounding
  // level, whether some f was not finite, and |dF| / |dY| over the stages (0 if dY = 0).
  double correction() const;
  // After finished(): the unknown that drove the iteration: one whose derivative was not
  // finite at a finite iterate, else the one whose last correction was largest against
  // its scale; -1 before any iteration.
  Eigen::Index worst_component() const;
  bool at_rounding() const;
  bool f_failed() const;
  double lipschitz_ratio() const;
  long evaluations_per_iteration() const;

  const RkTableau& tableau() const { return tableau_; }
  int implicit() const { return si_; }
  // The current stage values and their f, implicit stages only (index 0 = first implicit).
  // The full Newton iteration's f is of the iterate before the current one.
  const std::vector<Eigen::VectorXd>& y() const { return y_old_; }
  const std::vector<Eigen::VectorXd>& f() const { return f_old_; }
  // K_j of tableau stage j (0-based over all stages): f(t_n, x_n) for an explicit first
  // stage (as f(), of the iterate before for the full Newton iteration).
  const Eigen::VectorXd& stage_f(int j) const { return j < first_ ? *fx_ : f_old_[static_cast<std::size_t>(j - first_)]; }

 private:
  using Node = tbb::flow::continue_node<tbb::flow::continue_msg>;
  using Start = tbb::flow::broadcast_node<tbb::flow::continue_msg>;

  Eigen::Index slices() const { return (n_ + slice_ - 1) / slice_; }
  Eigen::Index slice_begin(Eigen::Index r) const { return r * slice_; }
  Eigen::Index slice_length(Eigen::Index r) const { return std::min(slice_, n_ - r * slice_); }
  // A stage's evaluations: one per slice, or one for a right-hand side that evaluates
  // whole vectors only (slices per evaluation: slices_per_f()); evaluation e's rows.
  Eigen::Index f_nodes() const { return problem_.sliceable ? slices() : 1; }
  Eigen::Index slices_per_f() const { return problem_.sliceable ? 1 : slices(); }
  RowRange f_node_range(Eigen::Index e) const {
    return {slice_begin(e * slices_per_f()), std::min(n_, slice_begin(e * slices_per_f() + slices_per_f()))};
  }
  bool newton() const { return is_newton(kind_); }
  bool full_newton() const { return kind_ == TirkIteration::newton; }
  void factorize(int k);
  void predict(int i, Eigen::Index e);
  void residual(Eigen::Index r);  // full Newton: R over slice r, loaded into the eigen split
  void update(Eigen::Index r);    // full Newton: Y_i += (T w)_i over slice r
  int layers() const { return newton() ? 1 : inner_; }
  void assemble(int i, Eigen::Index r);
  void substitute(int i, Eigen::Index r, int layer);
  void solve(int i);
  void evaluate(int i, Eigen::Index first_slice, Eigen::Index count);
  void measure(int i, Eigen::Index r, const Eigen::VectorXd& y_new, const Eigen::VectorXd& y_old);

  const RkTableau& tableau_;
  Eigen::MatrixXd t_;  // the splitting matrix over the implicit stages
  TirkIteration kind_;
  int inner_;
  const OdeProblem& problem_;
  int first_, si_;
  Eigen::Index n_, slice_;
  std::vector<Eigen::VectorXd> y_old_, y_new_, f_old_, f_new_, g_;
  std::vector<double> norm_;     // per stage and slice
  std::vector<char> roundoff_;   // per stage and slice
  std::vector<char> f_bad_;      // per stage and slice
  // Factorisations: one per distinct diagonal value of T.
  std::vector<double> diagonal_values_;
  std::vector<int> solver_of_stage_;
  std::vector<ShiftedSolver<double>> solvers_;
  std::vector<char> factor_failed_;
  // The full Newton iteration's systems, and the filter's own factorisation when gamma is
  // not a real eigenvalue of A (-1 in filter_system_ then).
  std::unique_ptr<EigenSplit> split_;
  int filter_system_ = -1;
  double filter_gamma_ = 0;
  ShiftedSolver<double> filter_;
  std::vector<Eigen::VectorXd> r_;
  const Eigen::SparseMatrix<double>* factor_jac_ = nullptr;
  double factor_tau_ = 0;
  LinearSolverKind factor_kind_ = LinearSolverKind::automatic;
  // The step.
  double t_n_ = 0, tau_ = 0;
  const Eigen::VectorXd* x_ = nullptr;
  const Eigen::VectorXd* fx_ = nullptr;
  const Eigen::VectorXd* scale_ = nullptr;
  // The graph.
  std::unique_ptr<Start> start_, factor_start_, predict_start_;
  std::vector<std::unique_ptr<Node>> nodes_;
  long token_ = 0;  // ThreadSanitizer's view of the node order (tsan_annotations.hpp)
};

}  // namespace mbsflow
