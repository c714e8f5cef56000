// The driver of the triangularised Runge-Kutta methods: iterations, Jacobian and
// factorisations, the embedded error estimate and the step control.
#include "mbsflow/error.hpp"
#include "mbsflow/methods/tirk_integrator.hpp"

#include <oneapi/tbb/task_arena.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "cubic_hermite.hpp"
#include "error_norm.hpp"
#include "settings_checks.hpp"
#include "starting_step.hpp"
#include "step_controller.hpp"
#include "tirk_stages.hpp"

namespace mbsflow {

const char* to_string(TirkIteration i) {
  switch (i) {
    case TirkIteration::jacobi: return "jacobi";
    case TirkIteration::triangular: return "triangular";
    case TirkIteration::diagonal: return "diagonal";
    case TirkIteration::newton_triangular: return "newton-triangular";
    case TirkIteration::newton_diagonal: return "newton-diagonal";
    case TirkIteration::newton: return "newton";
  }
  return "?";
}

TirkIteration tirk_iteration_from_string(const std::string& name) {
  for (TirkIteration i : {TirkIteration::jacobi, TirkIteration::triangular, TirkIteration::diagonal,
                          TirkIteration::newton_triangular, TirkIteration::newton_diagonal, TirkIteration::newton})
    if (name == to_string(i)) return i;
  throw InputError("unknown iteration '" + name +
                   "' (jacobi, triangular, diagonal, newton-triangular, newton-diagonal or newton)");
}

bool is_newton(TirkIteration i) {
  return i == TirkIteration::newton_triangular || i == TirkIteration::newton_diagonal || i == TirkIteration::newton;
}

Eigen::MatrixXd splitting_matrix(const TriangularSplitting& split, TirkIteration i) {
  switch (i) {
    case TirkIteration::jacobi: return Eigen::MatrixXd::Zero(split.d.size(), split.d.size());
    case TirkIteration::triangular:
    case TirkIteration::newton_triangular: return split.t_lower;
    case TirkIteration::newton: throw std::logic_error("splitting_matrix: the full Newton iteration has no splitting");
    default: return split.diagonal;
  }
}

double contraction_constant(const Eigen::MatrixXd& a, const Eigen::MatrixXd& t) {
  return (a - t).cwiseAbs().rowwise().sum().maxCoeff() + t.cwiseAbs().rowwise().sum().maxCoeff();
}

double newton_tolerance(double rtol, bool cheap_jacobian) {
  const double tol = cheap_jacobian ? std::min(0.03, std::sqrt(rtol)) : 0.03;
  return std::max(tol, 10 * std::numeric_limits<double>::epsilon() / rtol);
}

namespace {

// Below this many equations a system is small: a graph node's work takes about what its
// dispatch costs, and a Jacobian and its factorisation cost about as much as a few f
// evaluations (notes/methods-measurements.md, "Small systems").
constexpr Eigen::Index small_system = 1000;

// The embedded formula's gamma: for the full Newton iteration a real eigenvalue of A, whose
// system is factorised anyway; else (or without one) the largest pivot of the splitting.
EmbeddedFormula embedded_for(const RkTableau& tableau, const TriangularSplitting& split, TirkIteration iteration) {
  const double real = iteration == TirkIteration::newton ? largest_real_eigenvalue(tableau) : 0.0;
  return real > 0 ? embedded_formula(tableau, real) : embedded_formula(tableau, split);
}

void check_settings(const OdeProblem& p, const TirkSettings& s) {
  check_common_settings(p, s);
  if (s.fixed_iterations < 0 || s.max_iterations < 0) throw InputError("iteration counts must be >= 0");
  if (s.inner_iterations < 1) throw InputError("inner_iterations must be at least 1");
  if (!(s.refactor_ratio >= 0 && s.refactor_ratio < 1)) throw InputError("refactor_ratio must be in [0, 1)");
}

}  // namespace

class TirkIntegrator::Driver {
 public:
  Driver(const OdeProblem& p, const TirkSettings& s, std::function<void(double, Eigen::VectorXd&)> project = {})
      : p_(p), s_(s), project_(std::move(project)),
        tableau_(rk_tableau(s.tableau)),
        split_(ldu_splitting(tableau_.implicit_block())),
        embedded_(embedded_for(tableau_, split_, s.iteration)),
        t_matrix_(s.iteration == TirkIteration::newton ? tableau_.implicit_block() : splitting_matrix(split_, s.iteration)),
        arena_(s.threads > 0 ? s.threads : tbb::task_arena::automatic),
        stages_(tableau_, t_matrix_, s.iteration, s.inner_iterations, p,
                s.slice_size > 0 ? s.slice_size : p.size >= 8192 ? 4096 : p.size, embedded_.gamma),
        jacobian_(p, s.finite_difference_jacobian) {
    arena_.execute([&] {
      graph_ = std::make_unique<tbb::flow::graph>();
      stages_.build(*graph_);
    });
    // With one thread, or below 1000 equations, where a node's work takes a few
    // microseconds, about what the dispatch of its task costs (notes/methods-measurements.md,
    // "Small systems"), the graph's jobs run on this thread. Each node writes its own rows only,
    // so the numbers are the same either way. (colloc does so on one thread only: with more,
    // its two blocks of a step run side by side, each a whole iteration.)
    here_ = arena_.max_concurrency() == 1 || p.size < small_system;
    monitor_.tol = s.iteration_tol > 0 ? s.iteration_tol : newton_tolerance(s.rtol, cheap_newton());
    monitor_.predict_failure = full_newton();
    monitor_.max_iterations = s.max_iterations > 0 ? s.max_iterations : newton() ? 10 : 50;
    stiffly_accurate_ = stiffly_accurate(tableau_);
    const int stages = tableau_.stages(), si = stages_.implicit();
    end_weights_.resize(stages);
    error_weights_.resize(stages);
    for (int j = 0; j < stages; ++j) {
      end_weights_(j) = tableau_.b(j);
      error_weights_(j) = embedded_.bhat(j) - tableau_.b(j);
    }
    if (full_newton()) {  // (its A is regular: the eigen split needs that too)
      const Eigen::PartialPivLU<Eigen::MatrixXd> a_transposed(tableau_.implicit_block().transpose());
      end_d_ = a_transposed.solve(end_weights_.tail(si));
      error_d_ = a_transposed.solve(error_weights_.tail(si));
    }
    result_.stats.contraction_m = contraction_constant(tableau_.implicit_block(), t_matrix_);
    nodes_ = {0.0};
    node_stage_ = {-1};
    for (int i = 0; i < stages_.implicit(); ++i) {
      const double c = tableau_.c(tableau_.first_implicit() + i);
      if (std::none_of(nodes_.begin(), nodes_.end(), [c](double n) { return std::abs(n - c) < 1e-12; })) {
        nodes_.push_back(c);
        node_stage_.push_back(i);
      }
    }
  }

  // From problem.t0 and y0 (read again at every begin) towards problem.t_end.
  void begin();
  // One accepted step; false when the end is reached.
  bool advance();
  TirkResult& result() { return result_; }
  double t() const { return t_now_; }
  double tau() const { return tau_; }
  const Eigen::VectorXd& y() const { return x_; }
  const Eigen::VectorXd& f() const { return fx_; }
  // The last accepted step: its start, start value and derivative there.
  double t_old() const { return t_old_; }
  void save(StateWriter& out) const;
  void restore(StateReader& in);
  const Eigen::VectorXd& x_old() const { return x_old_; }
  const Eigen::VectorXd& f_old() const { return f_old_; }
  // One step from (t, x) iterated at most `count` times from the trivial predictor;
  // after(k) sees the stages after iteration k and returns false to stop. False when the
  // factorisation failed or an iterate was not finite.
  bool iterate_step(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau, int count,
                    const std::function<bool(int)>& after);
  const TirkStages& stages() const { return stages_; }
  const RkTableau& tableau() const { return tableau_; }

 private:
  void reset_controller() { controller_ = {s_.safety, s_.facmin, s_.facmax, monitor_.max_iterations, s_.predictive}; }
  bool newton() const { return is_newton(s_.iteration); }
  bool full_newton() const { return s_.iteration == TirkIteration::newton; }
  // Whether steps start from the extrapolated collocation polynomial (see extrapolate()).
  bool predicts() const {
    return (s_.iteration == TirkIteration::newton_triangular || full_newton()) && nodes_.size() >= 2;
  }
  void keep_or_renew_jacobian(double h);
  bool dear_jacobian() const;
  // The full Newton iteration on a small system whose Jacobian costs a few f evaluations:
  // Radau5's rules for the iteration's tolerance and the Jacobian's renewal apply as they
  // are. (On a large one, heat with N = 1e5, its renewal rule took 11 Jacobians and 32
  // factorisations where one and 22 did, for no gain in accuracy.)
  bool cheap_newton() const { return full_newton() && !dear_jacobian() && p_.size < small_system; }
  void begin_step(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau,
                  const std::vector<Eigen::VectorXd>* guess = nullptr);
  const std::vector<Eigen::VectorXd>* extrapolate(double t, double tau);
  bool factorize(const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau);
  bool iterate_once();
  bool iterate(int iterations);
  Eigen::VectorXd stage_sum(const Eigen::VectorXd& w, const Eigen::VectorXd& d, const Eigen::VectorXd& x, const Eigen::VectorXd& fx,
                            double tau) const;
  Eigen::VectorXd step_end(const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau) const;
  double estimate(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& x_new, const Eigen::VectorXd& fx, double tau,
                  bool first_or_rejected);
  [[noreturn]] void fail(const std::string& why, double tau, const char* hint = "") const;

  const OdeProblem& p_;
  const TirkSettings& s_;
  std::function<void(double, Eigen::VectorXd&)> project_;
  RkTableau tableau_;
  TriangularSplitting split_;
  EmbeddedFormula embedded_;
  // stage_sum()'s weights over all stages, and A^-T of their implicit part: b (the step's
  // end) and bhat - b (the error estimate).
  Eigen::VectorXd end_weights_, end_d_, error_weights_, error_d_;
  Eigen::MatrixXd t_matrix_;
  tbb::task_arena arena_;
  std::unique_ptr<tbb::flow::graph> graph_;  // declared before the stages: destroyed after their nodes
  TirkStages stages_;
  bool here_ = false;  // the graph's jobs on this thread (TirkStages::*_here)
  // One of the stages' jobs: on this thread, or through the graph.
  void run_job(void (TirkStages::*here)(), void (TirkStages::*start)()) {
    arena_.execute([&] {
      if (here_) {
        (stages_.*here)();
        return;
      }
      (stages_.*start)();
      graph_->wait_for_all();
    });
  }
  JacobianEvaluator jacobian_;
  Eigen::SparseMatrix<double> jac_;
  std::optional<LinearSolverKind> kind_;  // chosen for jac_'s pattern, which stays (a bandwidth scan of J)
  ConvergenceMonitor monitor_;
  StepController controller_;
  TirkResult result_;
  bool stiffly_accurate_ = false;
  double t_ = 0;
  Eigen::VectorXd scale_;
  bool jacobian_at_point_ = false, jacobian_stale_ = true;
  double factorized_tau_ = std::numeric_limits<double>::quiet_NaN();
  double theta_fresh_ = 0;      // the contraction rate in the last step with a Jacobian evaluated at its start
  Eigen::Index culprit_ = -1;  // the unknown that drove the last failed iteration
  // The predictor: the last accepted step (start, size, start value, stage values) and the
  // nodes of its collocation polynomial (0, then the distinct nonzero c of the implicit
  // stages node_stage_[k]).
  bool have_last_ = false, extrapolation_ok_ = true;
  double last_t_ = 0, last_h_ = 0;
  Eigen::VectorXd last_x_;
  std::vector<Eigen::VectorXd> last_y_, guess_;
  std::vector<double> nodes_;
  std::vector<int> node_stage_;
  int iterations_ = 0;
  // The stepping state: time, solution and f there, the step to try, and the last step's start.
  double t_now_ = 0, tau_ = 0, t_old_ = 0;
  Eigen::VectorXd x_, fx_, x_old_, f_old_;
  bool fixed_ = false, after_rejection_ = false;
  // Dear Jacobians only (dear_jacobian()): the step stays below 0.9 of the last one whose
  // iteration failed with an old Jacobian, a bound that grows by 2 % per accepted step.
  double h_cap_ = std::numeric_limits<double>::infinity();
  int renew_every_step_ = 0;  // accepted steps that still renew the Jacobian, after an old one failed
};

void TirkIntegrator::Driver::fail(const std::string& why, double tau, const char* hint) const {
  std::ostringstream os;
  os << why << " at t = " << t_ << " (step " << tau << ")" << hint;
  if (result_.stats.iteration_failures > 0 && culprit_ >= 0)
    os << "; the iteration failed " << result_.stats.iteration_failures << " times, last driven by "
       << (p_.describe ? p_.describe(culprit_) : "unknown " + std::to_string(culprit_));
  if (!newton()) {
    const TirkStats& st = result_.stats;
    const double l = std::max(st.lipschitz_start, st.lipschitz_observed);
    os << "; the " << to_string(s_.iteration) << " functional iteration contracts for tau < 1/(L M)";
    if (l > 0) os << " = " << 1.0 / (l * st.contraction_m);
    os << " (M = " << st.contraction_m << ", L >= " << l << " from |J(t0, y0)| and the iterates)";
  }
  throw RunError(os.str());
}

// I - tau t_ii J for every distinct t_ii (or the eigen systems of the full Newton
// iteration), J evaluated first when stale. Kept while J stays the same and tau is within
// refactor_ratio of the step they were factorised for. False when a matrix is singular.
bool TirkIntegrator::Driver::factorize(const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau) {
  TirkStats& st = result_.stats;
  const double ratio = full_newton() ? s_.refactor_ratio : 0.0;
  if (!jacobian_stale_ && std::abs(tau / factorized_tau_ - 1) <= ratio) return true;
  if (jacobian_stale_) {
    jac_ = jacobian_.evaluate(t_, x, fx, st.rhs_evaluations);
    ++st.jacobians;
    jacobian_at_point_ = true;
    jacobian_stale_ = false;
  }
  if (!kind_) kind_ = choose_linear_solver(jac_, s_.linear_solver);
  const LinearSolverKind kind = *kind_;
  stages_.request_factorization(jac_, tau, kind);
  st.factorizations += stages_.systems();
  st.linear_solver = kind;
  run_job(&TirkStages::factorize_here, &TirkStages::start_factorization);
  stages_.finished_factorization();
  factorized_tau_ = stages_.factorization_ok() ? tau : std::numeric_limits<double>::quiet_NaN();
  return stages_.factorization_ok();
}

// The triangular Newton-type iteration starts from the last accepted step's collocation
// polynomial (through its start x and its stage values Y_j at c_j), extrapolated to the
// new stage times, as Radau5 does: closer than Y_i = x, so fewer iterations. Null (the
// trivial predictor) for the first step, a shorter retry after a failed iteration, tableaux
// without distinct nonzero nodes, and the other schemes: the diagonal one amplifies the
// stiff components of the extrapolation error instead of damping them (it diverged on
// the heat equation at every step size).
const std::vector<Eigen::VectorXd>* TirkIntegrator::Driver::extrapolate(double t, double tau) {
  if (!predicts() || !have_last_ || !extrapolation_ok_) return nullptr;
  const int first = tableau_.first_implicit();
  guess_.resize(static_cast<std::size_t>(stages_.implicit()));
  for (int i = 0; i < stages_.implicit(); ++i) {
    const double c = tableau_.c(first + i);
    if (c == 0) continue;
    const double theta = (t + c * tau - last_t_) / last_h_;
    Eigen::VectorXd& g = guess_[static_cast<std::size_t>(i)];
    g.setZero(p_.size);
    for (std::size_t k = 0; k < nodes_.size(); ++k) {
      double l = 1;
      for (std::size_t m = 0; m < nodes_.size(); ++m)
        if (m != k) l *= (theta - nodes_[m]) / (nodes_[k] - nodes_[m]);
      g += l * (k == 0 ? last_x_ : last_y_[static_cast<std::size_t>(node_stage_[k])]);
    }
  }
  return &guess_;
}

// A renewal of the Jacobian is dear when differences would take more right-hand sides than
// two iterations of a step (the pattern's colours), whether it is differenced or not: the
// analytic Jacobians of multibody models cost as much as their differences or more
// (`mbsflow bench rhs`: A05 86 against 207 us, 22 right-hand sides; a 2000-body chain
// 4986 against 3472 ns per body), while those of small ODEs (2 to 4 colours) cost less
// than an iteration. Where the iteration then fails with an old Jacobian (and the step is
// not fixed, which only a fresh Jacobian can help), renewing it at every step for a while
// (what pays where renewals are cheap) costs more than shorter steps do: on IFToMM A05 at
// tol 1e-4, with differenced Jacobians the cap took 25 924 right-hand sides and 201
// Jacobians in place of 35 488 and 456, and with its analytic Jacobian 200 Jacobians and
// 404 factorisations in place of 451 and 1322 (0.14 s in place of 0.20 s); on Van der Pol,
// Robertson and B1 the cap would take up to 6x more right-hand sides (notes/methods-measurements.md).
bool TirkIntegrator::Driver::dear_jacobian() const { return jacobian_.colours() > 2 * tableau_.stages(); }

// After an accepted step of size h. Even with an exact Jacobian the triangular (or
// diagonal) splitting contracts at a rate of its own on the stiff components (about 0.3
// for Radau IIA), so a slow iteration is not by itself a sign of a stale Jacobian: the
// Jacobian is renewed when the rate exceeds both 0.3 (0.1 for the full Newton iteration)
// and 1.5 times the rate seen right after the last renewal, unless the matrices were kept
// from another step size: that mismatch slows the iteration too, and the extra iterations
// cost less than new factorisations (on the 2000-body chain, refactorising whenever the
// rate passed 0.1 took 27 factorisations in 59 steps). An iteration that fails with an old
// Jacobian renews it, and then (in advance()) either it is renewed at every step for the
// next 10, or, where Jacobians are dear (dear_jacobian()), the steps are kept shorter.
// On small systems whose Jacobians are cheap (cheap_newton()), Radau5's rule instead: renew after any step that
// took more than two iterations at a rate above 1e-3 (Robertson at rtol 1e-8: 11.9 digits
// against 9.5 with the rule above, in the same time; `mbsflow bench ivp`).
void TirkIntegrator::Driver::keep_or_renew_jacobian(double h) {
  const double theta = monitor_.theta;
  if (jacobian_at_point_)
    theta_fresh_ = theta;
  else if (cheap_newton() ? iterations_ > 2 && theta > 1e-3
                          : theta > std::max(full_newton() ? 0.1 : 0.3, 1.5 * theta_fresh_) && h == factorized_tau_)
    jacobian_stale_ = true;
  if (renew_every_step_ > 0) {
    --renew_every_step_;
    jacobian_stale_ = true;
  }
}

void TirkIntegrator::Driver::begin_step(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau,
                                        const std::vector<Eigen::VectorXd>* guess) {
  ++result_.stats.steps;
  t_ = t;
  scale_ = tolerance_weights(s_, x.array().abs());
  stages_.setup(t, tau, x, fx, scale_, guess);
  iterations_ = 0;
  run_job(&TirkStages::predict_here, &TirkStages::start_predictor);
  stages_.finished_predictor();
  result_.stats.rhs_evaluations += stages_.predictor_evaluations();
}

// One iteration through the graph; false when f was not finite.
bool TirkIntegrator::Driver::iterate_once() {
  run_job(&TirkStages::iterate_here, &TirkStages::start);
  stages_.finished();
  ++iterations_;
  ++result_.stats.iterations;
  result_.stats.rhs_evaluations += stages_.evaluations_per_iteration();
  if (!newton()) result_.stats.lipschitz_observed = std::max(result_.stats.lipschitz_observed, stages_.lipschitz_ratio());
  return !stages_.f_failed();
}

// Until converged, or exactly `iterations` times (> 0). False: diverged or failed.
bool TirkIntegrator::Driver::iterate(int iterations) {
  for (;;) {
    if (!iterate_once()) return false;
    const double norm = stages_.correction();
    if (iterations > 0) {
      if (!std::isfinite(norm)) return false;
      if (iterations_ >= iterations) return true;
      continue;
    }
    switch (monitor_.next(iterations_, norm, stages_.at_rounding())) {
      case IterationVerdict::iterate: continue;
      case IterationVerdict::converged: return true;
      case IterationVerdict::failed: return false;
    }
  }
}

// tau sum_j w_j K_j over the tableau's stages. The full Newton iteration has not evaluated
// its last iterate (as Radau5): its K_j come from the stage values, through
// Y_i = x + tau a_i0 fx + tau sum_j a_ij K_j over the implicit stages,
// tau sum_j w_j K_j = tau w_0 fx + sum_i d_i (Y_i - x - tau a_i0 fx) with A^T d = w.
// d: A^-T w over the implicit stages (end_d_ or error_d_, computed in the constructor).
Eigen::VectorXd TirkIntegrator::Driver::stage_sum(const Eigen::VectorXd& w, const Eigen::VectorXd& d, const Eigen::VectorXd& x,
                                                  const Eigen::VectorXd& fx, double tau) const {
  const int first = tableau_.first_implicit(), si = stages_.implicit();
  Eigen::VectorXd out = Eigen::VectorXd::Zero(p_.size);
  if (!full_newton()) {
    for (int j = 0; j < tableau_.stages(); ++j)
      if (w(j) != 0) out += (tau * w(j)) * stages_.stage_f(j);
    return out;
  }
  double explicit_weight = 0;
  for (int j = 0; j < first; ++j) explicit_weight += w(j);
  for (int i = 0; i < si; ++i) {
    if (d(i) == 0) continue;
    double a_explicit = 0;
    for (int j = 0; j < first; ++j) a_explicit += tableau_.a(first + i, j);
    out += d(i) * (stages_.y()[static_cast<std::size_t>(i)] - x);
    if (a_explicit != 0) out -= (d(i) * tau * a_explicit) * fx;
  }
  if (explicit_weight != 0) out += (tau * explicit_weight) * fx;
  return out;
}

// x_{n+1}: the last stage for a stiffly accurate method (Y_s, whose f is known), else
// x_n + tau sum b_i F_i.
Eigen::VectorXd TirkIntegrator::Driver::step_end(const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau) const {
  if (stiffly_accurate_) return stages_.y().back();
  return x + stage_sum(end_weights_, end_d_, x, fx, tau);
}

double TirkIntegrator::Driver::estimate(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& x_new, const Eigen::VectorXd& fx,
                                        double tau, bool first_or_rejected) {
  Eigen::VectorXd combination = (tau * embedded_.gamma) * fx + stage_sum(error_weights_, error_d_, x, fx, tau);
  Eigen::VectorXd e = combination;
  if (newton()) stages_.solve_with(embedded_.gamma, e);  // the stiff filter
  const Eigen::ArrayXd w = tolerance_weights(s_, x.array().abs().max(x_new.array().abs()));
  double err = weighted_rms(e, w);
  // Radau5's second filter (Hairer & Wanner IV.8): on the first step and after a rejection
  // a large estimate may be the stiff components the filter lets through; f at x + e in
  // place of f(x) filters them once more, so that a sound step is not cut, and a step that
  // is not sound is still rejected.
  if (newton() && err > 1 && first_or_rejected) {
    Eigen::VectorXd f1(p_.size);
    p_.evaluate(t, x + e, f1);
    ++result_.stats.rhs_evaluations;
    e = combination + (tau * embedded_.gamma) * (f1 - fx);
    stages_.solve_with(embedded_.gamma, e);
    err = weighted_rms(e, w);
  }
  return err;
}

void TirkIntegrator::Driver::begin() {
  TirkStats& st = result_.stats;
  double t = p_.t0;
  t_ = t;
  x_ = p_.y0;
  fx_.resize(p_.size);
  Eigen::VectorXd& x = x_;
  Eigen::VectorXd& fx = fx_;
  p_.evaluate(t, x, fx);
  ++st.rhs_evaluations;
  // L at the start, for the contraction bound of the functional iterations.
  jac_ = jacobian_.evaluate(t, x, fx, st.rhs_evaluations);
  ++st.jacobians;
  st.lipschitz_start = infinity_norm(jac_);
  jacobian_stale_ = false;
  jacobian_at_point_ = true;
  factorized_tau_ = std::numeric_limits<double>::quiet_NaN();
  fixed_ = s_.fixed_step > 0;
  tau_ = s_.fixed_step;
  if (!fixed_) {
    const Eigen::VectorXd scale = tolerance_weights(s_, x.array().abs());
    tau_ = s_.initial_step > 0 ? s_.initial_step : starting_step(p_, x, fx, scale, tableau_.order, st.rhs_evaluations);
  }
  t_now_ = t_old_ = t;
  have_last_ = false;
  h_cap_ = std::numeric_limits<double>::infinity();
  reset_controller();
  renew_every_step_ = 0;
  after_rejection_ = false;  // the step after a rejected one does not grow (Hairer & Wanner, IV.8)
}

// Checkpoints: the stepping state, the predictor's last step, the Jacobian and its
// bookkeeping, the step control, the counters, and the stages' factors.
void TirkIntegrator::Driver::save(StateWriter& out) const {
  out.text("tirk");
  for (double v : {t_, factorized_tau_, theta_fresh_, last_t_, last_h_, t_now_, tau_, t_old_, controller_.h_accepted,
                   controller_.err_accepted, h_cap_})
    out.real(v);
  for (bool v : {jacobian_at_point_, jacobian_stale_, have_last_, extrapolation_ok_, fixed_, after_rejection_}) out.flag(v);
  for (long v : {static_cast<long>(culprit_), static_cast<long>(iterations_), static_cast<long>(controller_.slow_growth),
                 static_cast<long>(renew_every_step_)})
    out.integer(v);
  for (const Eigen::VectorXd* v : {&scale_, &last_x_, &x_, &fx_, &x_old_, &f_old_}) out.vector(*v);
  out.vectors(last_y_);
  out.sparse(jac_);
  monitor_.save(out);
  const TirkStats& st = result_.stats;
  for (long v : {st.steps, st.accepted, st.rejected, st.iteration_failures, st.rhs_evaluations, st.jacobians,
                 st.factorizations, st.iterations})
    out.integer(v);
  out.integer(static_cast<int>(st.linear_solver));
  for (double v : {st.contraction_m, st.lipschitz_start, st.lipschitz_observed, st.largest_step}) out.real(v);
  stages_.save(out);
}

void TirkIntegrator::Driver::restore(StateReader& in) {
  in.expect("tirk");
  reset_controller();
  for (double* v : {&t_, &factorized_tau_, &theta_fresh_, &last_t_, &last_h_, &t_now_, &tau_, &t_old_,
                    &controller_.h_accepted, &controller_.err_accepted, &h_cap_})
    *v = in.real();
  for (bool* v : {&jacobian_at_point_, &jacobian_stale_, &have_last_, &extrapolation_ok_, &fixed_, &after_rejection_})
    *v = in.flag();
  culprit_ = in.integer(-1, p_.size);
  iterations_ = static_cast<int>(in.integer(0, 1 << 30));
  controller_.slow_growth = static_cast<int>(in.integer(0, 1 << 30));
  renew_every_step_ = static_cast<int>(in.integer(0, 1 << 30));
  for (Eigen::VectorXd* v : {&scale_, &last_x_, &x_, &fx_, &x_old_, &f_old_}) {
    *v = in.vector();
    if (v->size() != 0 && v->size() != p_.size) in.fail("tirk: a state vector of the wrong size");
  }
  last_y_ = in.vectors(p_.size);
  jac_ = in.sparse();
  monitor_.restore(in);
  TirkStats& st = result_.stats;
  for (long* v : {&st.steps, &st.accepted, &st.rejected, &st.iteration_failures, &st.rhs_evaluations, &st.jacobians,
                  &st.factorizations, &st.iterations})
    *v = in.integer(0, INT64_MAX);
  st.linear_solver = static_cast<LinearSolverKind>(in.integer(0, static_cast<int>(LinearSolverKind::sparselu)));
  for (double* v : {&st.contraction_m, &st.lipschitz_start, &st.lipschitz_observed, &st.largest_step}) *v = in.real();
  stages_.restore(in, jac_);
}

bool TirkIntegrator::Driver::advance() {
  TirkStats& st = result_.stats;
  double& t = t_now_;
  double& tau = tau_;
  Eigen::VectorXd& x = x_;
  Eigen::VectorXd& fx = fx_;
  const bool fixed = fixed_;
  bool& after_rejection = after_rejection_;
  const double t_end = p_.t_end, eps_t = end_tolerance(t_end);
  while (t_end - t > eps_t) {
    if (st.steps >= s_.max_steps) fail("reached the maximum number of steps", tau);
    if (const char* hint = step_underflow(tau, t, s_.min_step)) fail("step size underflow", tau, hint);
    const bool lands = tau >= t_end - t;
    const double h = lands ? t_end - t : tau;
    begin_step(t, x, fx, h, extrapolate(t, h));
    bool ok = !newton() || factorize(x, fx, h);
    // Matrices kept from another step size: the last step's rate says nothing about this
    // iteration, so it may not stop after one correction on the strength of it.
    if (ok && newton() && h != factorized_tau_) monitor_.eta = std::max(monitor_.eta, 1.0);
    ok = ok && iterate(s_.fixed_iterations);
    BlockStepRecord rec;
    rec.t = t;
    rec.tau = h;
    rec.iterations_s = iterations_;
    rec.iteration_failed = !ok;
    rec.error = std::numeric_limits<double>::quiet_NaN();
    if (!ok) {
      result_.steps.push_back(rec);
      ++st.iteration_failures;
      if (iterations_ > 0) culprit_ = stages_.worst_component();
      // A retry with a fresh Jacobian (same step) keeps the predictor: the old Jacobian, not
      // the guess, failed. On IFToMM A05 at tol 1e-4, restarting from Y_i = x took 4 or 5
      // iterations in each of these 200 retries, and 15 521 right-hand sides in all where
      // the predictor takes 13 704 (and a position error of 7.7e-4 m, not 9e-5). A shorter
      // step restarts from Y_i = x.
      extrapolation_ok_ = newton() && !jacobian_at_point_;
      ++st.rejected;
      // A fixed step cannot be shortened: only a Jacobian of the step's start may help.
      if (fixed && !(newton() && !jacobian_at_point_))
        fail(newton() ? "the Newton-type iteration did not converge" : "the functional iteration diverged", h);
      if (newton() && !jacobian_at_point_) {
        jacobian_stale_ = true;
        if (dear_jacobian() && !fixed)
          h_cap_ = 0.9 * h;  // this model outruns its Jacobians: shorter steps, so that one lasts longer
        else
          renew_every_step_ = 10;  // this model outruns its Jacobians: a fresh one per step for a while
      } else {
        tau = h * 0.5;
        renew_every_step_ = 0;  // a fresh Jacobian failed too: the step, not the Jacobian, was the trouble
        controller_.after_halving();  // grow slowly for a while (step_controller.hpp)
      }
      after_rejection = true;
      continue;
    }
    Eigen::VectorXd x_new = step_end(x, fx, h);
    double err = 0, fac = s_.facmax;
    if (!fixed) {
      err = estimate(t, x, x_new, fx, h, st.accepted == 0 || after_rejection);
      fac = controller_.factor(h, err, 1.0 / (embedded_.order + 1), iterations_, err <= 1);
    }
    rec.error = err;
    if (err > 1) {
      result_.steps.push_back(rec);
      ++st.rejected;
      tau = h * fac;
      after_rejection = true;
      continue;
    }
    if (after_rejection) fac = std::min(fac, 1.0);
    fac = controller_.limit_growth(fac);
    after_rejection = false;
    rec.taken = tableau_.stages();
    result_.steps.push_back(rec);
    ++st.accepted;
    st.largest_step = std::max(st.largest_step, h);
    if (newton()) keep_or_renew_jacobian(h);
    extrapolation_ok_ = true;
    if (predicts()) {
      have_last_ = true;
      last_t_ = t;
      last_h_ = h;
      last_x_ = x;
      last_y_ = stages_.y();
    }
    t_old_ = t;
    x_old_.swap(x);
    f_old_.swap(fx);
    fx.resize(p_.size);
    t = lands ? t_end : t + h;
    x = std::move(x_new);
    if (project_) project_(t, x);
    if (stiffly_accurate_ && !project_ && !full_newton()) {  // else f of the last iterate is not known
      fx = stages_.f().back();
    } else {
      p_.evaluate(t, x, fx);
      ++st.rhs_evaluations;
    }
    jacobian_at_point_ = false;
    // Radau5 keeps the step when it would grow by less than 1.2, to keep its factorisations;
    // with refactor_ratio the step may change that much and keep them anyway.
    if (!fixed) tau = newton() && (!full_newton() || s_.refactor_ratio == 0) && fac >= 1 && fac <= 1.2 ? h : h * fac;
    if (!fixed && std::isfinite(h_cap_)) {
      h_cap_ *= 1.02;
      tau = std::min(tau, h_cap_);
    }
    return true;
  }
  return false;
}

bool TirkIntegrator::Driver::iterate_step(double t, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, double tau, int count,
                          const std::function<bool(int)>& after) {
  begin_step(t, x, fx, tau);
  if (newton()) {
    jacobian_stale_ = true;
    if (!factorize(x, fx, tau)) return false;
  }
  for (int k = 1; k <= count; ++k) {
    if (!iterate_once() || !std::isfinite(stages_.correction())) return false;
    if (!after(k)) break;
  }
  return true;
}

TirkIntegrator::TirkIntegrator(const OdeProblem& problem, const TirkSettings& settings,
                               std::function<void(double, Eigen::VectorXd&)> project) {
  check_settings(problem, settings);
  d_ = std::make_unique<Driver>(problem, settings, std::move(project));
}
TirkIntegrator::~TirkIntegrator() = default;
void TirkIntegrator::begin() { d_->begin(); }
bool TirkIntegrator::advance() { return d_->advance(); }
double TirkIntegrator::t() const { return d_->t(); }
double TirkIntegrator::next_step() const { return d_->tau(); }
const Eigen::VectorXd& TirkIntegrator::y() const { return d_->y(); }
const TirkStats& TirkIntegrator::stats() const { return d_->result().stats; }
void TirkIntegrator::save(StateWriter& out) const { d_->save(out); }
void TirkIntegrator::restore(StateReader& in) { d_->restore(in); }

void TirkIntegrator::dense(double t, Eigen::VectorXd& out) const {
  cubic_hermite(d_->t_old(), d_->x_old(), d_->f_old(), d_->t(), d_->y(), d_->f(), t, out);
}

TirkResult integrate_tirk(const OdeProblem& problem, const TirkSettings& settings,
                          const std::function<void(double t, const Eigen::VectorXd& y)>& on_step) {
  TirkIntegrator integrator(problem, settings);
  integrator.begin();
  while (integrator.advance())
    if (on_step) on_step(integrator.t(), integrator.y());
  TirkResult& r = integrator.d_->result();
  r.t = integrator.t();
  r.y = integrator.y();
  return std::move(r);
}

IterationTrace trace_tirk_iterations(const OdeProblem& problem, const TirkSettings& settings, double t,
                                     const Eigen::VectorXd& x, double tau, int count) {
  check_settings(problem, settings);
  if (!(tau > 0) || count < 1) throw InputError("trace: the step and the iteration count must be positive");
  IterationTrace out;
  Eigen::VectorXd fx(problem.size);
  problem.evaluate(t, x, fx);
  // The converged stage values: newton-triangular until the corrections reach rounding.
  TirkSettings rs = settings;
  rs.iteration = TirkIteration::newton_triangular;
  TirkIntegrator::Driver reference(problem, rs);
  std::vector<Eigen::VectorXd> y_star;
  if (reference.iterate_step(t, x, fx, tau, 400, [&](int) { return !reference.stages().at_rounding(); })) {
    const TirkStages& st = reference.stages();
    const RkTableau& tab = reference.tableau();
    const int first = tab.first_implicit();
    double res = 0, size = 1;
    for (int i = 0; i < st.implicit(); ++i) {
      Eigen::VectorXd r = st.y()[static_cast<std::size_t>(i)] - x;
      for (int j = 0; j < tab.stages(); ++j)
        r -= (tau * tab.a(first + i, j)) * st.stage_f(j);
      res = std::max(res, r.cwiseAbs().maxCoeff());
      size = std::max(size, st.y()[static_cast<std::size_t>(i)].cwiseAbs().maxCoeff());
    }
    out.reference_residual = res / size;
    out.reference_ok = out.reference_residual <= 1e-10;
    y_star = st.y();
  }
  out.error.assign(static_cast<std::size_t>(count), std::numeric_limits<double>::quiet_NaN());
  out.evaluations.assign(static_cast<std::size_t>(count), 0);
  if (!out.reference_ok) return out;
  double size = 1;
  for (const Eigen::VectorXd& y : y_star) size = std::max(size, y.cwiseAbs().maxCoeff());
  TirkIntegrator::Driver scheme(problem, settings);
  std::fill(out.error.begin(), out.error.end(), std::numeric_limits<double>::infinity());
  scheme.iterate_step(t, x, fx, tau, count, [&](int k) {
    double e = 0;
    for (std::size_t i = 0; i < y_star.size(); ++i) e = std::max(e, (scheme.stages().y()[i] - y_star[i]).cwiseAbs().maxCoeff());
    out.error[static_cast<std::size_t>(k - 1)] = e / size;
    out.evaluations[static_cast<std::size_t>(k - 1)] = k * scheme.stages().evaluations_per_iteration();
    return true;
  });
  return out;
}

}  // namespace mbsflow
