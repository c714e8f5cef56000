#include "mbsflow/error.hpp"
#include "block_solve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "annotated_node.hpp"

namespace mbsflow {

namespace flow = tbb::flow;

BlockSolve::BlockSolve(const BlockCoefficients& method, const OdeProblem& problem, const BlockSettings& settings,
                       Eigen::Index slice_size)
    : method_(method),
      problem_(problem),
      kind_(settings.iteration),
      monitor_{settings.iteration_tol, settings.max_iterations > 0                       ? settings.max_iterations
                                       : settings.iteration == BlockIteration::newton ? 7
                                                                                      : 50},
      n_(problem.size),
      slice_(std::max<Eigen::Index>(1, std::min(slice_size, problem.size))) {
  const int k = points();
  u.assign(k, Eigen::VectorXd::Zero(n_));
  f.assign(k, Eigen::VectorXd::Zero(n_));
  b_.assign(k, Eigen::VectorXd::Zero(n_));
  slice_norm_.assign(static_cast<std::size_t>(slices()), 0.0);
  slice_at_roundoff_.assign(static_cast<std::size_t>(slices()), 0);
  f_not_finite_.assign(static_cast<std::size_t>(slices() * k), 0);
  if (kind_ != BlockIteration::newton) return;
  r_.assign(k, Eigen::VectorXd::Zero(n_));
  split_ = std::make_unique<EigenSplit>(method_.g, n_, "the block method's matrix g",
                                        make_elimination(problem.eliminable));
}

void BlockSolve::request_factorization(const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind) {
  factor_jac_ = &jac;
  factor_tau_ = tau;
  factor_kind_ = kind;
  factor_failed_.assign(static_cast<std::size_t>(systems()), 0);
}

void BlockSolve::start_factorization() {
  happens_before(&token_);
  factor_start_->try_put(flow::continue_msg());
}

bool BlockSolve::factorization_ok() const {
  return std::none_of(factor_failed_.begin(), factor_failed_.end(), [](char c) { return c != 0; });
}

void BlockSolve::factorize(int system) {
  try {
    split_->factorize(system, *factor_jac_, factor_tau_, factor_kind_);
  } catch (const RunError&) {
    factor_failed_[static_cast<std::size_t>(system)] = 1;
  }
}

void BlockSolve::save(StateWriter& out) const {
  monitor_.save(out);
  if (split_) split_->save(out);
}

void BlockSolve::restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern) {
  monitor_.restore(in);
  if (split_) split_->restore(in, pattern);
}

void BlockSolve::setup(double t0, double tau, const std::vector<Eigen::VectorXd>& past_u,
                       const std::vector<Eigen::VectorXd>& past_f, const Eigen::VectorXd& scale) {
  t0_ = t0;
  tau_ = tau;
  past_u_ = &past_u;
  past_f_ = &past_f;
  scale_ = &scale;
  iterations = 0;
  failed = false;
  evaluations = 0;
  // Blocks start from u_0 (the trivial predictor), so the first correction is the whole
  // step's change and the last step's rate says nothing about how close it is: the
  // iteration may not stop after it on the strength of that rate (Radau5's carried-over
  // rate presumes a start extrapolated from the last step). Without this, a component far
  // below the others (a per-component atol of 1e-20) ended 2e-3 off in relative terms.
  monitor_.eta = std::max(monitor_.eta, 1.0);
}

// B_i = sum_j q_ij u_j + tau sum_j d_ij f_j over the past points, and the starting
// iterate: u_0 for Newton, the Euler predictor u_0 + i tau f_0 for functional iteration.
void BlockSolve::prepare(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  const int k = points(), m = method_.spec.m;
  const Eigen::VectorXd& u0 = (*past_u_)[static_cast<std::size_t>(m - 1)];
  const Eigen::VectorXd& f0 = (*past_f_)[static_cast<std::size_t>(m - 1)];
  for (int i = 0; i < k; ++i) {
    auto bi = b_[i].segment(lo, len);
    bi.setZero();
    for (int j = 0; j < m; ++j) {
      if (method_.q(i, j) != 0) bi += method_.q(i, j) * (*past_u_)[static_cast<std::size_t>(j)].segment(lo, len);
      if (method_.d(i, j) != 0) bi += (tau_ * method_.d(i, j)) * (*past_f_)[static_cast<std::size_t>(j)].segment(lo, len);
    }
    if (kind_ == BlockIteration::newton)
      u[i].segment(lo, len) = u0.segment(lo, len);
    else
      u[i].segment(lo, len) = u0.segment(lo, len) + (method_.positions(i) * tau_) * f0.segment(lo, len);
  }
}

// f of point i over slices [first_slice, first_slice + slice_count).
void BlockSolve::evaluate(int i, Eigen::Index first_slice, Eigen::Index slice_count) {
  const Eigen::Index begin = slice_begin(first_slice), end = slice_begin(first_slice + slice_count - 1) +
                                                             slice_length(first_slice + slice_count - 1);
  problem_.rhs(t0_ + method_.positions(i) * tau_, u[i], f[i], {begin, end});
  f_not_finite_[static_cast<std::size_t>(first_slice * points() + i)] = !f[i].segment(begin, end - begin).allFinite();
}

// After f is evaluated at the latest iterate: converged, failed, or iterate again
// (convergence_monitor.hpp).
bool BlockSolve::gate() {
  evaluations += points();
  // f undefined at an iterate (outside the problem's domain): the step must be cut.
  if (std::any_of(f_not_finite_.begin(), f_not_finite_.end(), [](char c) { return c != 0; })) {
    failed = true;
    return false;
  }
  if (iterations == 0) return true;
  double norm = 0;
  for (double v : slice_norm_) norm = std::max(norm, v);
  const bool roundoff =
      std::all_of(slice_at_roundoff_.begin(), slice_at_roundoff_.end(), [](char c) { return c != 0; });
  switch (monitor_.next(iterations, norm, roundoff)) {
    case IterationVerdict::iterate: return true;
    case IterationVerdict::converged: return false;
    case IterationVerdict::failed: break;
  }
  failed = true;
  return false;
}

// z_e = -(T^-1 R)_e with the residuals R_l = U_l - B_l - tau sum_j g_lj F_j.
void BlockSolve::residual(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  const int k = points();
  for (int l = 0; l < k; ++l) {
    auto rl = r_[l].segment(lo, len);
    rl = u[l].segment(lo, len) - b_[l].segment(lo, len);
    for (int j = 0; j < k; ++j) rl -= (tau_ * method_.g(l, j)) * f[j].segment(lo, len);
  }
  split_->load_residuals(r_, lo, len);
}

void BlockSolve::solve(int e) { split_->solve(e); }

// dU = T w (a complex pair contributes twice the real part of one of its columns).
void BlockSolve::update(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  double norm = 0;
  bool roundoff = true;
  Eigen::VectorXd du(len);
  for (int i = 0; i < points(); ++i) {
    split_->correction(i, lo, len, du);
    u[i].segment(lo, len) += du;
    norm = std::max(norm, (du.array().abs() / scale_->segment(lo, len).array()).maxCoeff());
    roundoff = roundoff && at_roundoff(du, u[i].segment(lo, len));
  }
  slice_norm_[static_cast<std::size_t>(r)] = norm;
  slice_at_roundoff_[static_cast<std::size_t>(r)] = roundoff;
}

void BlockSolve::functional_update(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  double norm = 0;
  bool roundoff = true;
  Eigen::VectorXd next(len);
  for (int i = 0; i < points(); ++i) {
    next = b_[i].segment(lo, len);
    for (int j = 0; j < points(); ++j) next += (tau_ * method_.g(i, j)) * f[j].segment(lo, len);
    norm = std::max(norm, ((next - u[i].segment(lo, len)).array().abs() / scale_->segment(lo, len).array()).maxCoeff());
    roundoff = roundoff && at_roundoff(next - u[i].segment(lo, len), next);
    u[i].segment(lo, len) = next;
  }
  slice_norm_[static_cast<std::size_t>(r)] = norm;
  slice_at_roundoff_[static_cast<std::size_t>(r)] = roundoff;
}

void BlockSolve::build(flow::graph& g) {
  const Eigen::Index n_slices = slices();
  const int k = points();
  start_ = std::make_unique<Start>(g);
  evaluate_start_ = std::make_unique<Start>(g);
  correct_start_ = std::make_unique<Start>(g);
  factor_start_ = std::make_unique<Start>(g);
  auto node = [&](auto body) -> Node& { return annotated_node(g, nodes_, &token_, body); };
  // A join that fires `next` once all its predecessors are done.
  auto join = [&](Start& next) -> Node& { return node([&next] { next.try_put(flow::continue_msg()); }); };

  for (int e = 0; e < systems(); ++e) flow::make_edge(*factor_start_, node([this, e] { factorize(e); }));
  Node& prepared = join(*evaluate_start_);
  fan(node, *start_, prepared, n_slices, [this](Eigen::Index r) { prepare(r); });
  Node& gate_node = node([this] {
    if (gate()) {
      ++iterations;
      correct_start_->try_put(flow::continue_msg());
    }
  });
  // A right-hand side that evaluates whole vectors only gets one node per point (asked
  // per slice it would compute everything once per slice).
  const Eigen::Index f_slices = problem_.sliceable ? n_slices : 1, per_node = problem_.sliceable ? 1 : n_slices;
  for (int i = 0; i < k; ++i)
    for (Eigen::Index r = 0; r < f_slices; ++r) {
      Node& e = node([this, i, r, per_node] { evaluate(i, r * per_node, per_node); });
      flow::make_edge(*evaluate_start_, e);
      flow::make_edge(e, gate_node);
    }
  Node& corrected = join(*evaluate_start_);
  if (kind_ == BlockIteration::functional) {
    fan(node, *correct_start_, corrected, n_slices, [this](Eigen::Index r) { functional_update(r); });
    captures_published();
    return;
  }
  Node& residuals_done = node([] {});
  fan(node, *correct_start_, residuals_done, n_slices, [this](Eigen::Index r) { residual(r); });
  Node& solved = node([] {});
  fan(node, residuals_done, solved, systems(), [this](Eigen::Index e) { solve(static_cast<int>(e)); });
  fan(node, solved, corrected, n_slices, [this](Eigen::Index r) { update(r); });
  captures_published();
}

void BlockSolve::start() {
  happens_before(&token_);
  start_->try_put(flow::continue_msg());
}

void BlockSolve::finished() { happens_after(&token_); }

void BlockSolve::run_inline() {
  const Eigen::Index n_slices = slices();
  const Eigen::Index f_slices = problem_.sliceable ? n_slices : 1, per_node = problem_.sliceable ? 1 : n_slices;
  for (Eigen::Index r = 0; r < n_slices; ++r) prepare(r);
  for (;;) {
    for (int i = 0; i < points(); ++i)
      for (Eigen::Index r = 0; r < f_slices; ++r) evaluate(i, r * per_node, per_node);
    if (!gate()) return;
    ++iterations;
    if (kind_ == BlockIteration::functional) {
      for (Eigen::Index r = 0; r < n_slices; ++r) functional_update(r);
      continue;
    }
    for (Eigen::Index r = 0; r < n_slices; ++r) residual(r);
    for (int e = 0; e < systems(); ++e) solve(e);
    for (Eigen::Index r = 0; r < n_slices; ++r) update(r);
  }
}

void BlockSolve::factorize_inline() {
  for (int e = 0; e < systems(); ++e) factorize(e);
}



}  // namespace mbsflow
