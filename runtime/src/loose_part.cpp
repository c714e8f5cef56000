#include "loose_part.hpp"

#include "mbsflow/graph/error.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "step_grid.hpp"

namespace mbsflow::loose {

// The local system whose ghost bodies follow the extrapolation, whatever the integrator
// puts in their places; their derivatives are zero.
struct LoosePart::Ghosted {
  LoosePart& lp;
  Eigen::Index dimension() const { return lp.part.system.dimension(); }
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    lp.work_ = y;
    lp.extrapolate_ghosts(t, lp.work_);
    lp.part.system.rhs(t, lp.work_, dydt);
    const StateLayout& l = lp.part.system.layout();
    const Eigen::Index own = lp.part.own, ghosts = l.bodies - own;
    dydt.segment(l.position(own), 3 * ghosts).setZero();
    dydt.segment(l.orientation(own), 4 * ghosts).setZero();
    dydt.segment(l.velocity(own), 3 * ghosts).setZero();
    dydt.segment(l.angular_velocity(own), 3 * ghosts).setZero();
  }
};

LoosePart::LoosePart(const Model& model, const Submodel& sub, const RunOptions& o, int extrapolation, int max_lag)
    : part(model, sub, extrapolation + 1), o_(o), order_(extrapolation), lag_(max_lag) {
  if (o.method == Method::rk4) {
    rk4_ = std::make_unique<Rk4>(part.system.dimension());
  } else {
    Dopri5Settings s;
    s.rtol = o.rtol;
    s.atol = o.atol;
    dopri5_ = std::make_unique<Dopri5>(part.system.dimension(), s);
    h_ = o.step;
  }
}

void LoosePart::make_past(double t0, double H) {
  Eigen::VectorXd f0(part.system.dimension());
  part.system.rhs(t0, part.x[0], f0);  // own bodies exact: the ghosts are the true initial values
  for (int j = 1; j <= order_; ++j) part.x[static_cast<std::size_t>(j)] = part.x[0] - (j * H) * f0;
}

void LoosePart::start(double t0, double H) {
  for (int j = order_; j >= 1; --j) samples_.emplace_front(t0 - j * H, part.x[static_cast<std::size_t>(j)]);
  samples_.emplace_front(t0, part.x[0]);
}

// Lagrange weights at t over the samples held (fewer at the start: lower order).
std::vector<double> LoosePart::weights(double t) const {
  const std::size_t n = samples_.size();
  std::vector<double> w(n, 1.0);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t m = 0; m < n; ++m)
      if (m != j) w[j] *= (t - samples_[m].first) / (samples_[j].first - samples_[m].first);
  return w;
}

void LoosePart::extrapolate_ghosts(double t, Eigen::VectorXd& y) const {
  const std::vector<double> w = weights(t);
  const StateLayout& l = part.system.layout();
  const Eigen::Index own = part.own, ghosts = l.bodies - own;
  auto field = [&](Eigen::Index (StateLayout::*offset)(Eigen::Index) const, int n) {
    auto dst = y.segment((l.*offset)(own), n * ghosts);
    dst.setZero();
    for (std::size_t j = 0; j < w.size(); ++j) dst += w[j] * samples_[j].second.segment((l.*offset)(own), n * ghosts);
  };
  field(&StateLayout::position, 3);
  field(&StateLayout::orientation, 4);
  field(&StateLayout::velocity, 3);
  field(&StateLayout::angular_velocity, 3);
  for (Eigen::Index g = own; g < l.bodies; ++g) y.segment<4>(l.orientation(g)).normalize();
}

void LoosePart::integrate(double t0, double t1) {
  Ghosted sys{*this};
  Eigen::VectorXd& y = part.x[0];
  if (rk4_) {
    const StepGrid grid = step_grid(t0, t1, o_.step);
    for (long k = 0; k < grid.steps; ++k) {
      rk4_->step(sys, grid.time(k), grid.time(k + 1) - grid.time(k), y);
      part.system.after_step(grid.time(k + 1), y);
    }
    steps += grid.steps;
    evaluations += 4 * grid.steps;
    return;
  }
  Dopri5& dp = *dopri5_;
  dp.invalidate();  // the ghosts moved on: the stored derivative is stale
  const long before_rejected = dp.stats().rejected, before_accepted = dp.stats().accepted;
  double t = t0;
  while (t < t1) {
    h_ = std::min(h_, t1 - t);
    double taken = 0.0;
    if (!dp.step(sys, t, h_, y, taken)) throw RunError(step_collapsed_message(h_, t, o_.rtol));
    const double t_new = landed_time(t, taken, t1);
    part.system.after_step(t_new, y);
    dp.invalidate();
    t = t_new;
  }
  steps += dp.stats().accepted - before_accepted;
  rejected += dp.stats().rejected - before_rejected;
  evaluations = dp.stats().evaluations;
}

CouplingError LoosePart::error(double t1) {
  guess_ = part.x[0];
  extrapolate_ghosts(t1, guess_);
  const StateLayout& l = part.system.layout();
  CouplingError e;
  for (Eigen::Index g = part.own; g < l.bodies; ++g) {
    e.position = std::max(e.position, (guess_.segment<3>(l.position(g)) - part.x[0].segment<3>(l.position(g))).norm());
    e.velocity = std::max(e.velocity, (guess_.segment<3>(l.velocity(g)) - part.x[0].segment<3>(l.velocity(g))).norm());
  }
  return e;
}

void LoosePart::push(double t1) {
  samples_.emplace_front(t1, part.x[0]);
  while (static_cast<int>(samples_.size()) > order_ + 1) samples_.pop_back();
}

void LoosePart::save() {
  saved_ = part.x[0];
  saved_h_ = h_;
}

void LoosePart::restore(long index) {
  part.x[0] = saved_;
  h_ = saved_h_;
  while (!kept_.empty() && std::get<0>(kept_.back()) >= index) kept_.pop_back();
}

void LoosePart::keep(long index, double t) {
  kept_.emplace_back(index, t, part.x[0]);
  while (static_cast<int>(kept_.size()) > lag_ + 1) kept_.pop_front();
}

const Eigen::VectorXd& LoosePart::kept(long index) const {
  for (const auto& [i, t, x] : kept_)
    if (i == index) return x;
  throw RunError("internal: the state of macro step " + std::to_string(index) + " is no longer kept");
}

double LoosePart::kept_time(long index) const {
  for (const auto& [i, t, x] : kept_)
    if (i == index) return t;
  throw RunError("internal: the state of macro step " + std::to_string(index) + " is no longer kept");
}

double next_macro_end(const StepGrid& grid, long output_every, long next_out, double t, double H, bool* on_output) {
  // Macro steps land on the output grid (and the end), so snapshots fall on it; the output
  // times are the tight run's step times, to the bit.
  const double t_out = grid.time(std::min(next_out * output_every, grid.steps));
  *on_output = t + H >= t_out - 1e-12 * std::max(1.0, std::abs(t_out));
  return *on_output ? t_out : t + H;
}

}  // namespace mbsflow::loose
