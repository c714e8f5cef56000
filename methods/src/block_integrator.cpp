// The driver of the block methods: start-up, the window of past points, the Jacobian and
// factorisations, and the seed's step control from the s- and (s+1)-point blocks.
#include "mbsflow/error.hpp"
#include "mbsflow/methods/block_integrator.hpp"

#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "block_solve.hpp"
#include "error_norm.hpp"
#include "settings_checks.hpp"
#include "starting_step.hpp"
#include "step_controller.hpp"
#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "tsan_annotations.hpp"

namespace mbsflow {

const char* to_string(BlockIteration i) { return i == BlockIteration::newton ? "newton" : "functional"; }

BlockIteration block_iteration_from_string(const std::string& name) {
  if (name == "newton") return BlockIteration::newton;
  if (name == "functional") return BlockIteration::functional;
  throw InputError("unknown iteration '" + name + "' (newton or functional)");
}

Eigen::VectorXd AcceptedBlock::interpolate(double t) const {
  const DenseWeights w = dense_output_weights(*method, (t - t0) / tau);
  const int m = method->spec.m;
  Eigen::VectorXd y = Eigen::VectorXd::Zero((*u)[0].size());
  for (int j = 0; j < m; ++j) {
    if (w.wu(j) != 0) y += w.wu(j) * (*past_u)[static_cast<std::size_t>(j)];
    if (w.wd(j) != 0) y += (tau * w.wd(j)) * (*past_f)[static_cast<std::size_t>(j)];
  }
  for (int i = 0; i < points; ++i)
    if (w.wg(i) != 0) y += (tau * w.wg(i)) * (*f)[static_cast<std::size_t>(i)];
  return y;
}

namespace {

void check_settings(const OdeProblem& p, const BlockSettings& s) {
  check_common_settings(p, s);
  if (!(s.global_fraction >= 0 && s.global_fraction <= 1)) throw InputError("global_fraction must be in [0, 1] (0: the method's default)");
  if (!(s.refactor_ratio >= 0 && s.refactor_ratio < 1)) throw InputError("refactor_ratio must be in [0, 1)");
}

// The last accepted block (or the start-up block), kept for the dense output that
// rebuilds the window of a multistep method when the step changes.
struct LastBlock {
  const BlockCoefficients* method = nullptr;
  double t0 = 0, tau = 0;
  std::vector<Eigen::VectorXd> past_u, past_f, u, f;
  AcceptedBlock view() const { return {t0, tau, static_cast<int>(u.size()), method, &past_u, &past_f, &u, &f}; }
};

// The first m - 1 points of a multistep method come from a one-step block method with
// max(s, m - 1, p - 1) points at the same spacing, of order at least p (so the start does
// not lower the order).
BlockMethodSpec start_up_method(const BlockMethodSpec& s) {
  return {1, std::max({s.s, s.m - 1, s.effective_order() - 1}), 0};
}

}  // namespace

class BlockIntegrator::Driver {
 public:
  Driver(const OdeProblem& p, const BlockSettings& s, std::function<void(const AcceptedBlock&)> on_block,
         std::function<void(double, Eigen::VectorXd&)> project)
      : p_(p), s_(s), on_block_(std::move(on_block)), project_(std::move(project)),
        fixed_(s.fixed_step > 0),
        slice_(s.slice_size > 0 ? s.slice_size : p.size >= 8192 ? 4096 : p.size),
        arena_(s.threads > 0 ? s.threads : tbb::task_arena::automatic),
        small_(generate_block_method(s.method), p, s, slice_),
        large_(generate_block_method(step_control_partner(s.method)), p, s, slice_) {
    if (s.method.m > 1) starter_ = std::make_unique<BlockSolve>(generate_block_method(start_up_method(s.method)), p, s, slice_);
    // On one thread the graph only adds a task's dispatch per node: the blocks' jobs run on
    // this thread, in one of the graph's orders (the same numbers). With more threads the
    // graph stays even for small systems: its two blocks of a step run side by side.
    inline_ = arena_.max_concurrency() == 1;
    // A flow graph runs its nodes in the arena it was made in.
    arena_.execute([&] {
      graph_ = std::make_unique<tbb::flow::graph>();
      small_.build(*graph_);
      if (!fixed_) large_.build(*graph_);
      if (starter_) starter_->build(*graph_);
    });
    if (s.iteration == BlockIteration::newton) jacobian_ = std::make_unique<JacobianEvaluator>(p, s.finite_difference_jacobian);
  }

  // From problem.t0 and y0 (read again at every begin) towards problem.t_end.
  void begin();
  // One accepted block; false when the end is reached. RunError when the step falls below
  // the minimum or max_steps is reached.
  bool advance();
  BlockResult& result() { return result_; }
  double t() const { return t_; }
  double tau() const { return tau_; }
  const Eigen::VectorXd& y() const { return past_u_.back(); }
  void save(StateWriter& out) const;
  void restore(StateReader& in);

 private:
  int block_id(const BlockSolve* b) const { return b == &small_ ? 1 : b == &large_ ? 2 : b && b == starter_.get() ? 3 : 0; }
  BlockSolve* block_of(int id) { return id == 1 ? &small_ : id == 2 ? &large_ : id == 3 ? starter_.get() : nullptr; }
  // The block whose method the last block used (none before the first).
  const BlockSolve* block_with(const BlockCoefficients* method) const {
    for (const BlockSolve* b : {&small_, &large_, static_cast<const BlockSolve*>(starter_.get())})
      if (b && method == &b->method()) return b;
    return nullptr;
  }
  void reset_controller() {
    controller_ = {s_.safety, s_.facmin, s_.facmax, s_.max_iterations > 0 ? s_.max_iterations : 7, s_.predictive};
  }
  int m() const { return s_.method.m; }
  bool newton() const { return s_.iteration == BlockIteration::newton; }
  void rebuild_window(double tau);
  bool solve(std::initializer_list<BlockSolve*> blocks, double tau);
  // A job of the blocks: each on this thread (inline_), or all through the graph.
  void run_blocks(std::initializer_list<BlockSolve*> blocks, void (BlockSolve::*here)(), void (BlockSolve::*start)()) {
    if (inline_) {
      for (BlockSolve* b : blocks) (b->*here)();
      return;
    }
    arena_.execute([&] {
      for (BlockSolve* b : blocks) (b->*start)();
      graph_->wait_for_all();
    });
  }
  bool factorize(std::initializer_list<BlockSolve*> blocks, double tau);
  void accept(const BlockSolve& b, double tau);
  void record(double tau, int taken, double error, const BlockSolve& a, const BlockSolve* b = nullptr);
  double block_difference() const;

  const OdeProblem& p_;
  const BlockSettings& s_;
  std::function<void(const AcceptedBlock&)> on_block_;
  std::function<void(double, Eigen::VectorXd&)> project_;
  bool fixed_;
  bool inline_ = false;  // the blocks' iterations on this thread, not through the graph
  Eigen::Index slice_;
  tbb::task_arena arena_;
  std::unique_ptr<tbb::flow::graph> graph_;  // declared first: destroyed after the nodes below
  BlockSolve small_, large_;
  std::unique_ptr<BlockSolve> starter_;
  std::unique_ptr<JacobianEvaluator> jacobian_;
  Eigen::SparseMatrix<double> jac_;
  std::optional<LinearSolverKind> kind_;  // chosen for jac_'s pattern, which stays (a bandwidth scan of J)
  BlockResult result_;
  double t_ = 0;
  double tau_ = 0;  // the step (point spacing) to try next
  double window_tau_ = 0;
  std::vector<Eigen::VectorXd> past_u_, past_f_;  // the window: m points, oldest first
  Eigen::VectorXd scale_;
  LastBlock last_;
  StepController controller_;
  bool after_rejection_ = false;  // no step growth right after a rejection
  bool jacobian_at_point_ = false;  // evaluated at the window's last point
  bool jacobian_stale_ = true;      // to be evaluated (again) before the next factorisation
  const BlockSolve* factorized_for_ = nullptr;
  double factorized_tau_ = std::numeric_limits<double>::quiet_NaN();
};

void BlockIntegrator::Driver::record(double tau, int taken, double error, const BlockSolve& a, const BlockSolve* b) {
  BlockStepRecord r;
  r.t = t_;
  r.tau = tau;
  r.taken = taken;
  r.error = error;
  r.iterations_s = a.iterations;
  r.iterations_s1 = b ? b->iterations : 0;
  r.iteration_failed = a.failed || (b && b->failed);
  result_.steps.push_back(r);
}

// Factorises I - tau mu_e J for every system of the blocks (in parallel), evaluating J
// first when it is stale (or not yet taken). Kept while J stays the same and tau is within
// refactor_ratio of the step they were factorised for. False when a matrix is singular (or
// J is not finite): the step is then retried smaller.
bool BlockIntegrator::Driver::factorize(std::initializer_list<BlockSolve*> blocks, double tau) {
  BlockStats& st = result_.stats;
  if (jacobian_stale_) {
    jac_ = jacobian_->evaluate(t_, past_u_.back(), past_f_.back(), st.rhs_evaluations);
    ++st.jacobians;
    jacobian_at_point_ = true;
    jacobian_stale_ = false;
    factorized_for_ = nullptr;
  }
  const double ratio = s_.refactor_ratio;
  if (factorized_for_ == *blocks.begin() && std::abs(tau / factorized_tau_ - 1) <= ratio) return true;
  if (!kind_) kind_ = choose_linear_solver(jac_, s_.linear_solver);
  const LinearSolverKind kind = *kind_;
  for (BlockSolve* b : blocks) {
    b->request_factorization(jac_, tau, kind);
    st.factorizations += b->systems();
  }
  st.linear_solver = kind;
  factorized_for_ = nullptr;
  run_blocks(blocks, &BlockSolve::factorize_inline, &BlockSolve::start_factorization);
  bool ok = true;
  for (BlockSolve* b : blocks) {
    b->finished();
    ok = ok && b->factorization_ok();
  }
  if (!ok) return false;
  factorized_tau_ = tau;
  factorized_for_ = *blocks.begin();
  return true;
}

bool BlockIntegrator::Driver::solve(std::initializer_list<BlockSolve*> blocks, double tau) {
  ++result_.stats.steps;
  scale_ = tolerance_weights(s_, past_u_.back().array().abs());
  for (BlockSolve* b : blocks) b->setup(t_, tau, past_u_, past_f_, scale_);
  if (newton() && !factorize(blocks, tau)) {
    for (BlockSolve* b : blocks) b->failed = true;
    return false;
  }
  run_blocks(blocks, &BlockSolve::run_inline, &BlockSolve::start);
  bool ok = true;
  for (BlockSolve* b : blocks) {
    b->finished();
    result_.stats.rhs_evaluations += b->evaluations;
    result_.stats.iterations += b->iterations;
    ok = ok && !b->failed;
  }
  return ok;
}

// Largest difference of the two blocks over the points they share, in the weighted RMS norm.
double BlockIntegrator::Driver::block_difference() const {
  double err = 0;
  const Eigen::VectorXd& ps = small_.method().positions;
  const Eigen::VectorXd& pl = large_.method().positions;
  for (int i = 0; i < small_.points(); ++i)
    for (int j = 0; j < large_.points(); ++j) {
      if (std::abs(ps(i) - pl(j)) > 1e-12) continue;
      const Eigen::ArrayXd w = tolerance_weights(s_, past_u_.back().array().abs().max(large_.u[j].array().abs()));
      err = std::max(err, weighted_rms(large_.u[j] - small_.u[i], w));
    }
  return err;
}

void BlockIntegrator::Driver::accept(const BlockSolve& b, double tau) {
  const int k = b.points();
  if (on_block_) on_block_({t_, tau, k, &b.method(), &past_u_, &past_f_, &b.u, &b.f});
  if (m() > 1) {  // kept for rebuilding the window when the step changes
    last_.method = &b.method();
    last_.t0 = t_;
    last_.tau = tau;
    last_.past_u = past_u_;
    last_.past_f = past_f_;
    last_.u = b.u;
    last_.f = b.f;
  }
  // The new window: the last m of (old window of w points, block points); after the
  // start-up it grows from 1 to m. Entry a is combined point w + k - m + a >= a, so an old
  // entry is read before it is overwritten.
  const int w = static_cast<int>(past_u_.size());
  past_u_.resize(static_cast<std::size_t>(m()));
  past_f_.resize(static_cast<std::size_t>(m()));
  for (int a = 0; a < m(); ++a) {
    const int c = w + k - m() + a;
    const auto at = static_cast<std::size_t>(a);
    past_u_[at] = c < w ? past_u_[static_cast<std::size_t>(c)] : b.u[static_cast<std::size_t>(c - w)];
    past_f_[at] = c < w ? past_f_[static_cast<std::size_t>(c)] : b.f[static_cast<std::size_t>(c - w)];
  }
  t_ += b.method().span() * tau;
  if (project_) {
    // f at the projected point: the next Jacobian's differences are taken from it (with the
    // block's f at the unprojected point they were off by (f(u) - f(u_projected)) / delta,
    // and Newton failed on every model with rigid joints), and multistep blocks read it.
    project_(t_, past_u_.back());
    p_.evaluate(t_, past_u_.back(), past_f_.back());
    ++result_.stats.rhs_evaluations;
  }
  window_tau_ = tau;
  jacobian_at_point_ = false;
  ++result_.stats.accepted;
}

// A multistep method whose step changed: its past points at the new spacing from the
// last block's collocation polynomial, and f evaluated there.
void BlockIntegrator::Driver::rebuild_window(double tau) {
  const AcceptedBlock view = last_.view();
  for (int j = 1; j < m(); ++j) {
    const double tj = t_ - j * tau;
    const std::size_t at = static_cast<std::size_t>(m() - 1 - j);
    past_u_[at] = view.interpolate(tj);
    p_.evaluate(tj, past_u_[at], past_f_[at]);
    ++result_.stats.rhs_evaluations;
  }
  window_tau_ = tau;
}

void BlockIntegrator::Driver::begin() {
  BlockStats& st = result_.stats;
  t_ = p_.t0;
  past_u_ = {p_.y0};
  past_f_ = {Eigen::VectorXd(p_.size)};
  p_.evaluate(t_, past_u_[0], past_f_[0]);
  ++st.rhs_evaluations;
  window_tau_ = 0;
  jacobian_stale_ = true;
  jacobian_at_point_ = false;
  factorized_for_ = nullptr;
  after_rejection_ = false;
  reset_controller();
  tau_ = s_.fixed_step;
  if (!fixed_) {
    scale_ = tolerance_weights(s_, p_.y0.array().abs());
    tau_ = s_.initial_step > 0 ? s_.initial_step
                               : starting_step(p_, p_.y0, past_f_[0], scale_, small_.method().order, st.rhs_evaluations);
  }
}

bool BlockIntegrator::Driver::advance() {
  BlockStats& st = result_.stats;
  const int s = s_.method.s, q = small_.method().order;
  double& tau = tau_;
  const double t_end = p_.t_end, eps_t = end_tolerance(t_end);
  auto fail = [&](const std::string& why, const char* hint = "") {
    std::ostringstream os;
    os << why << " at t = " << t_ << " (step " << tau << ")" << hint;
    throw RunError(os.str());
  };
  // After an iteration that did not converge: a fresh Jacobian first, then a smaller step
  // that grows slowly for a while (step_controller.hpp; A05, tol 1e-4: 141 rejections in
  // 679 blocks, 422 in 624 when a halving could grow back at once).
  auto iteration_failed = [&] {
    ++st.iteration_failures;
    ++st.rejected;
    after_rejection_ = true;
    if (newton() && !jacobian_at_point_) {
      jacobian_stale_ = true;
    } else {
      tau *= 0.5;
      controller_.after_halving();
    }
  };
  while (t_end - t_ > eps_t) {
    if (st.steps >= s_.max_steps) fail("reached the maximum number of steps");
    if (const char* hint = step_underflow(tau, t_, s_.min_step)) fail("step size underflow", hint);
    if (past_u_.size() < static_cast<std::size_t>(m())) {  // start-up of a multistep method
      tau = std::min(tau, (t_end - t_) / starter_->points());
      if (!solve({starter_.get()}, tau)) {
        record(tau, 0, std::numeric_limits<double>::quiet_NaN(), *starter_);
        iteration_failed();
        continue;
      }
      record(tau, starter_->points(), 0, *starter_);
      accept(*starter_, tau);
      return true;
    }
    bool allow_large = !fixed_;
    const double left = t_end - t_, span_s = small_.method().span(), span_s1 = large_.method().span();
    if (span_s == span_s1) {
      if (left <= span_s * tau) tau = left / span_s;  // both blocks land on the end
    } else if (left < (span_s + 0.5) * tau) {
      tau = left / span_s;  // the s-point block lands on the end
      allow_large = false;
    } else if (left < span_s1 * tau) {
      tau = left / span_s1;  // the (s+1)-point block lands on the end
    }
    if (m() > 1 && tau != window_tau_) rebuild_window(tau);
    const bool ok = fixed_ ? solve({&small_}, tau) : solve({&small_, &large_}, tau);
    if (!ok) {
      record(tau, 0, std::numeric_limits<double>::quiet_NaN(), small_, fixed_ ? nullptr : &large_);
      iteration_failed();
      continue;
    }
    if (fixed_) {
      record(tau, s, 0, small_);
      accept(small_, tau);
      return true;
    }
    // At Radau points the difference at the end is the s-point block's local error,
    // O(tau^(q+1)); equidistant blocks keep the seed's exponent 1/q.
    const bool radau = s_.method.nodes == BlockNodes::radau;
    const double err = block_difference(), gf = s_.global_fraction > 0 ? s_.global_fraction : radau ? 1.0 : 0.1;
    const double exponent = radau ? 1.0 / (q + 1) : 1.0 / q;
    const int taken = err <= gf && allow_large ? s + 1 : err <= 1 ? s : 0;
    double fac = controller_.factor(tau, err / gf, exponent, std::max(small_.iterations, large_.iterations), taken > 0);
    record(tau, taken, err, small_, &large_);
    if (taken == 0) {
      ++st.rejected;
      after_rejection_ = true;
      tau *= std::min(fac, 0.9);
      continue;
    }
    if (after_rejection_) fac = std::min(fac, 1.0);
    fac = controller_.limit_growth(fac);
    after_rejection_ = false;
    // A Newton iteration that needed more than three corrections: a fresh Jacobian for the
    // next block (blocks start from u_0 and take 4-5 even on a fresh one; after more than
    // two, J was renewed on nearly every block). (Renewing only when the contraction rate
    // grows, as tirk does, and starting blocks from the last block's polynomial, as Radau5
    // does, were measured with bench ivp against the rule at two and are worse here: the
    // extrapolated start failed on Van der Pol mu = 1e6 at two tolerances and took 318
    // blocks on Robertson at rtol 1e-6 where that rule took 107.)
    if (newton() && (small_.iterations > 3 || large_.iterations > 3)) jacobian_stale_ = true;
    double tau_new = tau * fac;
    if (newton() && s_.refactor_ratio == 0 && fac >= 1 && fac <= 1.2) tau_new = tau;  // keep the factorisations
    if (m() > 1) tau_new = std::min(tau_new, tau * double(taken + m() - 1) / double(m() - 1));
    if (taken == s + 1) {
      ++st.taken_s1;
      accept(large_, tau);
    } else {
      ++st.taken_s;
      accept(small_, tau);
    }
    tau = tau_new;
    return true;
  }
  return false;
}

// Checkpoints: the window, the last block (multistep methods rebuild the window from it),
// the step control, the Jacobian and which blocks' factors are current, and each block's
// iteration memory and factors.
void BlockIntegrator::Driver::save(StateWriter& out) const {
  out.text("colloc");
  for (double v : {t_, tau_, window_tau_, controller_.h_accepted, controller_.err_accepted, factorized_tau_}) out.real(v);
  for (bool v : {after_rejection_, jacobian_at_point_, jacobian_stale_}) out.flag(v);
  out.integer(block_id(factorized_for_));
  out.integer(controller_.slow_growth);
  out.vectors(past_u_);
  out.vectors(past_f_);
  out.integer(block_id(block_with(last_.method)));
  out.real(last_.t0);
  out.real(last_.tau);
  for (const auto* v : {&last_.past_u, &last_.past_f, &last_.u, &last_.f}) out.vectors(*v);
  out.sparse(jac_);
  const BlockStats& st = result_.stats;
  for (long v : {st.steps, st.accepted, st.rejected, st.taken_s1, st.taken_s, st.iteration_failures, st.rhs_evaluations,
                 st.jacobians, st.factorizations, st.iterations})
    out.integer(v);
  out.integer(static_cast<int>(st.linear_solver));
  small_.save(out);
  large_.save(out);
  if (starter_) starter_->save(out);
}

void BlockIntegrator::Driver::restore(StateReader& in) {
  in.expect("colloc");
  reset_controller();
  for (double* v : {&t_, &tau_, &window_tau_, &controller_.h_accepted, &controller_.err_accepted, &factorized_tau_}) *v = in.real();
  for (bool* v : {&after_rejection_, &jacobian_at_point_, &jacobian_stale_}) *v = in.flag();
  factorized_for_ = block_of(static_cast<int>(in.integer(0, 3)));
  controller_.slow_growth = static_cast<int>(in.integer(0, 1 << 30));
  past_u_ = in.vectors(p_.size);
  past_f_ = in.vectors(p_.size);
  if (past_u_.empty() || past_u_.size() != past_f_.size() || past_u_.size() > static_cast<std::size_t>(m()))
    in.fail("colloc: the window of past points does not fit the method");
  const BlockSolve* last = block_of(static_cast<int>(in.integer(0, 3)));
  last_.method = last ? &last->method() : nullptr;
  last_.t0 = in.real();
  last_.tau = in.real();
  for (auto* v : {&last_.past_u, &last_.past_f, &last_.u, &last_.f}) *v = in.vectors(p_.size);
  jac_ = in.sparse();
  BlockStats& st = result_.stats;
  for (long* v : {&st.steps, &st.accepted, &st.rejected, &st.taken_s1, &st.taken_s, &st.iteration_failures,
                  &st.rhs_evaluations, &st.jacobians, &st.factorizations, &st.iterations})
    *v = in.integer(0, INT64_MAX);
  st.linear_solver = static_cast<LinearSolverKind>(in.integer(0, static_cast<int>(LinearSolverKind::sparselu)));
  small_.restore(in, jac_);
  large_.restore(in, jac_);
  if (starter_) starter_->restore(in, jac_);
}

BlockIntegrator::BlockIntegrator(const OdeProblem& problem, const BlockSettings& settings,
                                 std::function<void(const AcceptedBlock&)> on_block,
                                 std::function<void(double, Eigen::VectorXd&)> project) {
  check_settings(problem, settings);
  d_ = std::make_unique<Driver>(problem, settings, std::move(on_block), std::move(project));
}
BlockIntegrator::~BlockIntegrator() = default;
void BlockIntegrator::begin() { d_->begin(); }
bool BlockIntegrator::advance() { return d_->advance(); }
double BlockIntegrator::t() const { return d_->t(); }
double BlockIntegrator::next_step() const { return d_->tau(); }
const Eigen::VectorXd& BlockIntegrator::y() const { return d_->y(); }
const BlockStats& BlockIntegrator::stats() const { return d_->result().stats; }
void BlockIntegrator::save(StateWriter& out) const { d_->save(out); }
void BlockIntegrator::restore(StateReader& in) { d_->restore(in); }

BlockResult integrate_block(const OdeProblem& problem, const BlockSettings& settings,
                            const std::function<void(const AcceptedBlock&)>& on_block) {
  BlockIntegrator integrator(problem, settings, on_block);
  integrator.begin();
  while (integrator.advance()) {
  }
  BlockResult& r = integrator.d_->result();
  r.t = integrator.t();
  r.y = integrator.y();
  return std::move(r);
}

}  // namespace mbsflow
