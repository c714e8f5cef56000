#include "mbsflow/error.hpp"
#include "tirk_stages.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "annotated_node.hpp"

namespace mbsflow {

namespace flow = tbb::flow;

TirkStages::TirkStages(const RkTableau& tableau, const Eigen::MatrixXd& t, TirkIteration kind, int inner_iterations,
                       const OdeProblem& problem, Eigen::Index slice_size, double filter_gamma)
    : tableau_(tableau),
      t_(t),
      kind_(kind),
      inner_(kind == TirkIteration::jacobi ? 1 : std::max(1, inner_iterations)),
      problem_(problem),
      first_(tableau.first_implicit()),
      si_(tableau.implicit_stages()),
      n_(problem.size),
      slice_(std::max<Eigen::Index>(1, std::min(slice_size, problem.size))) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n_);
  for (auto* v : {&y_old_, &y_new_, &f_old_, &f_new_, &g_}) v->assign(static_cast<std::size_t>(si_), zero);
  const auto cells = static_cast<std::size_t>(si_ * slices());
  norm_.assign(cells, 0.0);
  roundoff_.assign(cells, 0);
  f_bad_.assign(cells, 0);
  if (!newton()) return;
  filter_gamma_ = filter_gamma;
  const std::shared_ptr<Elimination> elimination = make_elimination(problem.eliminable);
  filter_.eliminate_first(elimination);
  if (full_newton()) {
    split_ = std::make_unique<EigenSplit>(tableau.implicit_block(), n_, "the matrix A of tableau " + tableau.name,
                                          elimination);
    filter_system_ = split_->real_system(filter_gamma);
    r_.assign(static_cast<std::size_t>(si_), zero);
    return;
  }
  for (int i = 0; i < si_; ++i) {
    const double v = t_(i, i);
    if (!(v > 0)) throw InputError("Newton-type iteration: the diagonal of T must be positive");
    auto same = std::find_if(diagonal_values_.begin(), diagonal_values_.end(),
                             [v](double w) { return std::abs(v - w) <= 1e-14 * std::max(v, w); });
    if (same == diagonal_values_.end()) {
      solver_of_stage_.push_back(static_cast<int>(diagonal_values_.size()));
      diagonal_values_.push_back(v);
    } else {
      solver_of_stage_.push_back(static_cast<int>(same - diagonal_values_.begin()));
    }
  }
  solvers_.resize(diagonal_values_.size());
  for (ShiftedSolver<double>& s : solvers_) s.eliminate_first(elimination);
}

void TirkStages::save(StateWriter& out) const {
  for (const ShiftedSolver<double>& s : solvers_) s.save(out);
  if (split_) split_->save(out);
  filter_.save(out);
}

void TirkStages::restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern) {
  for (ShiftedSolver<double>& s : solvers_) s.restore(in, pattern);
  if (split_) split_->restore(in, pattern);
  filter_.restore(in, pattern);
}

void TirkStages::request_factorization(const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind) {
  factor_jac_ = &jac;
  factor_tau_ = tau;
  factor_kind_ = kind;
  factor_failed_.assign(static_cast<std::size_t>(systems()), 0);
}

int TirkStages::systems() const {
  if (full_newton()) return split_->systems() + (filter_system_ < 0 ? 1 : 0);
  return static_cast<int>(solvers_.size());
}

void TirkStages::factorize(int k) {
  const auto at = static_cast<std::size_t>(k);
  try {
    if (!full_newton())
      solvers_[at].factorize(*factor_jac_, factor_tau_ * diagonal_values_[at], factor_kind_);
    else if (k < split_->systems())
      split_->factorize(k, *factor_jac_, factor_tau_, factor_kind_);
    else
      filter_.factorize(*factor_jac_, factor_tau_ * filter_gamma_, factor_kind_);
  } catch (const RunError&) {
    factor_failed_[at] = 1;
  }
}

void TirkStages::start_factorization() {
  happens_before(&token_);
  factor_start_->try_put(flow::continue_msg());
}

void TirkStages::finished_factorization() { happens_after(&token_); }

bool TirkStages::factorization_ok() const {
  return std::none_of(factor_failed_.begin(), factor_failed_.end(), [](char c) { return c != 0; });
}

void TirkStages::solve_with(double gamma, Eigen::VectorXd& v) const {
  if (full_newton() && std::abs(gamma - filter_gamma_) <= 1e-14 * gamma)
    return filter_system_ >= 0 ? split_->solve_real(filter_system_, v) : filter_.solve(v);
  for (std::size_t k = 0; k < diagonal_values_.size(); ++k)
    if (std::abs(diagonal_values_[k] - gamma) <= 1e-14 * gamma) return solvers_[k].solve(v);
  throw std::logic_error("solve_with: no factorisation for this diagonal value");
}

void TirkStages::setup(double t, double tau, const Eigen::VectorXd& x, const Eigen::VectorXd& fx, const Eigen::VectorXd& scale,
                       const std::vector<Eigen::VectorXd>* guess) {
  t_n_ = t;
  tau_ = tau;
  x_ = &x;
  fx_ = &fx;
  scale_ = &scale;
  for (int i = 0; i < si_; ++i) {
    const auto at = static_cast<std::size_t>(i);
    y_old_[at] = guess && tableau_.c(first_ + i) != 0 ? (*guess)[at] : x;
    f_old_[at] = fx;
  }
}

void TirkStages::start_predictor() {
  happens_before(&token_);
  predict_start_->try_put(flow::continue_msg());
}

void TirkStages::finished_predictor() { happens_after(&token_); }

long TirkStages::predictor_evaluations() const {
  if (full_newton()) return 0;
  long n = 0;
  for (int i = 0; i < si_; ++i) n += tableau_.c(first_ + i) != 0;
  return n;
}

void TirkStages::assemble(int i, Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  const auto at = static_cast<std::size_t>(i);
  const int row = first_ + i;
  auto g = g_[at].segment(lo, len);
  g = x_->segment(lo, len);
  for (int j = 0; j < tableau_.stages(); ++j) {
    const double a = tableau_.a(row, j);
    if (a == 0) continue;
    g += (tau_ * a) * stage_f(j).segment(lo, len);
  }
  for (int j = 0; j < i; ++j)
    if (t_(i, j) != 0)
      g += (tau_ * t_(i, j)) *
           (f_new_[static_cast<std::size_t>(j)].segment(lo, len) - f_old_[static_cast<std::size_t>(j)].segment(lo, len));
  if (newton()) {
    g -= y_old_[at].segment(lo, len);  // the Newton residual
    return;
  }
  y_new_[at].segment(lo, len) = g;
  if (layers() == 1) measure(i, r, y_new_[at], y_old_[at]);
}

// Another substitution for the stage's own term: Y_i = G_i + tau t_ii (f(Y_i) - F_i^old).
void TirkStages::substitute(int i, Eigen::Index r, int layer) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  const auto at = static_cast<std::size_t>(i);
  y_new_[at].segment(lo, len) =
      g_[at].segment(lo, len) + (tau_ * t_(i, i)) * (f_new_[at].segment(lo, len) - f_old_[at].segment(lo, len));
  if (layer == layers() - 1) measure(i, r, y_new_[at], y_old_[at]);
}

void TirkStages::solve(int i) {
  const auto at = static_cast<std::size_t>(i);
  solvers_[static_cast<std::size_t>(solver_of_stage_[at])].solve(g_[at]);
  y_new_[at] = y_old_[at] + g_[at];
  for (Eigen::Index r = 0; r < slices(); ++r) measure(i, r, y_new_[at], y_old_[at]);
}

void TirkStages::residual(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  for (int i = 0; i < si_; ++i) {
    auto ri = r_[static_cast<std::size_t>(i)].segment(lo, len);
    ri = y_old_[static_cast<std::size_t>(i)].segment(lo, len) - x_->segment(lo, len);
    for (int j = 0; j < tableau_.stages(); ++j) {
      const double a = tableau_.a(first_ + i, j);
      if (a != 0) ri -= (tau_ * a) * stage_f(j).segment(lo, len);
    }
  }
  split_->load_residuals(r_, lo, len);
}

void TirkStages::update(Eigen::Index r) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  Eigen::VectorXd du;
  for (int i = 0; i < si_; ++i) {
    const auto at = static_cast<std::size_t>(i);
    split_->correction(i, lo, len, du);
    y_new_[at].segment(lo, len) = y_old_[at].segment(lo, len) + du;
    measure(i, r, y_new_[at], y_old_[at]);
  }
}

// F_i = f(Y_i): of the new iterate (the splittings, after their update), or of the
// current one (the full Newton iteration, before its residuals).
void TirkStages::evaluate(int i, Eigen::Index first_slice, Eigen::Index count) {
  const auto at = static_cast<std::size_t>(i);
  const Eigen::VectorXd& y = full_newton() ? y_old_[at] : y_new_[at];
  Eigen::VectorXd& f = full_newton() ? f_old_[at] : f_new_[at];
  const Eigen::Index begin = slice_begin(first_slice), end = slice_begin(first_slice + count - 1) + slice_length(first_slice + count - 1);
  problem_.rhs(t_n_ + tableau_.c(first_ + i) * tau_, y, f, {begin, end});
  for (Eigen::Index r = first_slice; r < first_slice + count; ++r)
    f_bad_[static_cast<std::size_t>(i * slices() + r)] = !f.segment(slice_begin(r), slice_length(r)).allFinite();
}

void TirkStages::measure(int i, Eigen::Index r, const Eigen::VectorXd& y_new, const Eigen::VectorXd& y_old) {
  const Eigen::Index lo = slice_begin(r), len = slice_length(r);
  const auto dy = y_new.segment(lo, len) - y_old.segment(lo, len);
  const auto cell = static_cast<std::size_t>(i * slices() + r);
  norm_[cell] = (dy.array().abs() / scale_->segment(lo, len).array()).maxCoeff();
  roundoff_[cell] = at_roundoff(dy, y_new.segment(lo, len));
}

void TirkStages::build(flow::graph& g) {
  const Eigen::Index n_slices = slices();
  // A right-hand side that evaluates whole vectors only gets one node per stage.
  const Eigen::Index f_nodes = this->f_nodes(), per_node = slices_per_f();
  start_ = std::make_unique<Start>(g);
  factor_start_ = std::make_unique<Start>(g);
  predict_start_ = std::make_unique<Start>(g);
  auto node = [&](auto body) -> Node& { return annotated_node(g, nodes_, &token_, body); };
  for (int i = 0; i < si_ && !full_newton(); ++i) {
    if (tableau_.c(first_ + i) == 0) continue;  // f(t_n, x) is known
    for (Eigen::Index e = 0; e < f_nodes; ++e)
      flow::make_edge(*predict_start_, node([this, i, e] { predict(i, e); }));
  }
  for (int k = 0; k < systems(); ++k) flow::make_edge(*factor_start_, node([this, k] { factorize(k); }));
  if (full_newton()) {
    // f(stage, slice) -> residual(slice) -> solve(system) -> update(slice)
    Node& evaluated = node([] {});
    for (int i = 0; i < si_; ++i)
      for (Eigen::Index e = 0; e < f_nodes; ++e) {
        Node& ev = node([this, i, e, per_node] { evaluate(i, e * per_node, per_node); });
        flow::make_edge(*start_, ev);
        flow::make_edge(ev, evaluated);
      }
    Node& residuals_done = node([] {});
    fan(node, evaluated, residuals_done, n_slices, [this](Eigen::Index r) { residual(r); });
    Node& solved = node([] {});
    fan(node, residuals_done, solved, split_->systems(), [this](Eigen::Index e) { split_->solve(static_cast<int>(e)); });
    Node& written = node([] {});
    fan(node, solved, written, n_slices, [this](Eigen::Index r) { update(r); });
    captures_published();
    return;
  }
  // final_eval[i][e]: the last evaluation nodes of stage i, which later stages wait for.
  std::vector<std::vector<Node*>> final_eval(static_cast<std::size_t>(si_));
  for (int i = 0; i < si_; ++i) {
    std::vector<Node*> layer;  // the nodes that write Y_i in the current layer
    for (Eigen::Index r = 0; r < n_slices; ++r) {
      Node& a = node([this, i, r] { assemble(i, r); });
      bool waits = false;
      if (kind_ == TirkIteration::triangular || kind_ == TirkIteration::newton_triangular)
        for (int j = 0; j < i; ++j)
          if (t_(i, j) != 0) {
            flow::make_edge(*final_eval[static_cast<std::size_t>(j)][static_cast<std::size_t>(r / per_node)], a);
            waits = true;
          }
      if (!waits) flow::make_edge(*start_, a);
      layer.push_back(&a);
    }
    if (newton()) {
      Node& s = node([this, i] { solve(i); });
      for (Node* a : layer) flow::make_edge(*a, s);
      layer = {&s};
    }
    for (int l = 0; l < layers(); ++l) {
      Node& written = node([] {});
      for (Node* w : layer) flow::make_edge(*w, written);
      std::vector<Node*> evals;
      for (Eigen::Index e = 0; e < f_nodes; ++e) {
        Node& ev = node([this, i, e, per_node] { evaluate(i, e * per_node, per_node); });
        flow::make_edge(written, ev);
        evals.push_back(&ev);
      }
      if (l == layers() - 1) {
        final_eval[static_cast<std::size_t>(i)] = evals;
        break;
      }
      Node& evaluated = node([] {});
      for (Node* ev : evals) flow::make_edge(*ev, evaluated);
      layer.clear();
      for (Eigen::Index r = 0; r < n_slices; ++r) {
        Node& sub = node([this, i, r, l] { substitute(i, r, l + 1); });
        flow::make_edge(evaluated, sub);
        layer.push_back(&sub);
      }
    }
  }
  captures_published();
}

void TirkStages::factorize_here() {
  for (int k = 0; k < systems(); ++k) factorize(k);
}

// The predictor's f at stage i of the last step's polynomial, evaluation e's rows.
void TirkStages::predict(int i, Eigen::Index e) {
  const auto at = static_cast<std::size_t>(i);
  problem_.rhs(t_n_ + tableau_.c(first_ + i) * tau_, y_old_[at], f_old_[at], f_node_range(e));
}

void TirkStages::predict_here() {
  for (int i = 0; i < si_ && !full_newton(); ++i) {
    if (tableau_.c(first_ + i) == 0) continue;
    for (Eigen::Index e = 0; e < f_nodes(); ++e) predict(i, e);
  }
}

void TirkStages::iterate_here() {
  const Eigen::Index n_slices = slices(), per_node = slices_per_f();
  if (full_newton()) {
    for (int i = 0; i < si_; ++i)
      for (Eigen::Index e = 0; e < f_nodes(); ++e) evaluate(i, e * per_node, per_node);
    for (Eigen::Index r = 0; r < n_slices; ++r) residual(r);
    for (int e = 0; e < split_->systems(); ++e) split_->solve(e);
    for (Eigen::Index r = 0; r < n_slices; ++r) update(r);
    return;
  }
  // Stage by stage: a stage waits for the earlier ones' last evaluations (triangular), or
  // reads none of their new values (Jacobi).
  for (int i = 0; i < si_; ++i) {
    for (Eigen::Index r = 0; r < n_slices; ++r) assemble(i, r);
    if (newton()) solve(i);
    for (int l = 0; l < layers(); ++l) {
      for (Eigen::Index e = 0; e < f_nodes(); ++e) evaluate(i, e * per_node, per_node);
      if (l == layers() - 1) break;
      for (Eigen::Index r = 0; r < n_slices; ++r) substitute(i, r, l + 1);
    }
  }
}

void TirkStages::start() {
  happens_before(&token_);
  start_->try_put(flow::continue_msg());
}

void TirkStages::finished() {
  happens_after(&token_);
  std::swap(y_old_, y_new_);
  if (!full_newton()) std::swap(f_old_, f_new_);  // the full Newton iteration's f is of the iterate before
}

double TirkStages::correction() const { return *std::max_element(norm_.begin(), norm_.end()); }

Eigen::Index TirkStages::worst_component() const {
  if (!scale_) return -1;
  // Where non-finite numbers came from: a derivative that is not finite at a finite
  // iterate (the linear solve then spreads them to every coupled unknown).
  // (The full Newton iteration's f is of the iterate before the last, now in y_new_.)
  for (const auto* pair : {&y_new_, &y_old_}) {
    if (full_newton() && pair == &y_old_) break;
    const auto& f = pair == &y_new_ && !full_newton() ? f_new_ : f_old_;
    for (int i = 0; i < si_; ++i) {
      const auto at = static_cast<std::size_t>(i);
      for (Eigen::Index k = 0; k < n_; ++k)
        if (std::isfinite((*pair)[at](k)) && !std::isfinite(f[at](k))) return k;
    }
  }
  Eigen::Index worst = -1;
  double largest = -1;
  for (int i = 0; i < si_; ++i) {
    const auto at = static_cast<std::size_t>(i);
    for (Eigen::Index k = 0; k < n_; ++k) {
      const double c = std::abs(y_old_[at](k) - y_new_[at](k)) / (*scale_)(k);
      const double key = std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
      if (key > largest) {
        largest = key;
        worst = k;
      }
    }
  }
  return worst;
}

bool TirkStages::at_rounding() const {
  return std::all_of(roundoff_.begin(), roundoff_.end(), [](char c) { return c != 0; });
}

bool TirkStages::f_failed() const {
  return std::any_of(f_bad_.begin(), f_bad_.end(), [](char c) { return c != 0; });
}

// After finished(): old and new have been swapped, so the previous iterate is in *_new_.
double TirkStages::lipschitz_ratio() const {
  double df = 0, dy = 0;
  for (int i = 0; i < si_; ++i) {
    const auto at = static_cast<std::size_t>(i);
    df = std::max(df, (f_old_[at] - f_new_[at]).cwiseAbs().maxCoeff());
    dy = std::max(dy, (y_old_[at] - y_new_[at]).cwiseAbs().maxCoeff());
  }
  return dy > 0 ? df / dy : 0.0;
}

long TirkStages::evaluations_per_iteration() const { return static_cast<long>(si_) * layers(); }

}  // namespace mbsflow
