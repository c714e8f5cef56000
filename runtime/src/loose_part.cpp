#include "loose_part.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "mbsflow/error.hpp"
#include "mbsflow/runtime/divergence.hpp"
#include "mbsflow/runtime/eliminable.hpp"
#include "sink_runner.hpp"

namespace mbsflow::loose {

namespace {
constexpr int numbers = partitioned::body_numbers;

// Lagrange weights at t over the sample times (fewer samples at the start: lower order).
template <class Samples>
void lagrange_weights(const Samples& s, double t, double* w) {
  const std::size_t n = s.size();
  for (std::size_t j = 0; j < n; ++j) {
    w[j] = 1.0;
    for (std::size_t m = 0; m < n; ++m)
      if (m != j) w[j] *= (t - s[m].t) / (s[j].t - s[m].t);
  }
}
}  // namespace

// The local system whose ghost bodies follow the extrapolation, whatever the integrator
// puts in their places; their derivatives are zero. rhs()'s phases, with the ghosts'
// kinematics taken again from their extrapolated values (in work_'s ghost slots): the
// same arithmetic as rhs() of y with the ghosts replaced, without copying y.
void LoosePart::ghosted_rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
  extrapolate_ghosts(t, work_);
  MultibodySystem& s = part.system;
  s.kinematics_for_rhs(t, y);
  s.kinematics_of(t, work_, ghost_bodies_);
  s.compute_joint_forces();
  dydt.resize(y.size());
  s.compute_derivatives(t, y, dydt);
  const StateLayout& l = part.system.layout();
  const Eigen::Index own = part.sub->integrated(), ghosts = l.bodies - own;
  dydt.segment(l.position(own), 3 * ghosts).setZero();
  dydt.segment(l.orientation(own), 4 * ghosts).setZero();
  dydt.segment(l.velocity(own), 3 * ghosts).setZero();
  dydt.segment(l.angular_velocity(own), 3 * ghosts).setZero();
}

LoosePart::LoosePart(const Model& model, const Submodel& sub, const RunOptions& o, Method method, int extrapolation,
                     int retain)
    : part(model, sub, extrapolation + 1), o_(o), order_(extrapolation), retain_(static_cast<std::size_t>(retain)),
      history_(sub.exchanges.size()), predicted_(sub.exchanges.size()), ghost_at_(sub.exchanges.size()),
      borrowed_at_(sub.exchanges.size()), ghost_slots_(sub.exchanges.size()) {
  work_ = part.x[0];
  for (int g = sub.integrated(); g < static_cast<int>(part.system.layout().bodies); ++g) ghost_bodies_.push_back(g);
  for (std::size_t e = 0; e < sub.exchanges.size(); ++e) {
    const std::vector<int>& to = sub.exchanges[e].to;
    for (std::size_t i = 0; i < to.size(); ++i)
      (to[i] < sub.integrated() ? borrowed_at_ : ghost_at_)[e].push_back(static_cast<int>(i));
    for (int i : ghost_at_[e]) ghost_slots_[e].push_back(to[static_cast<std::size_t>(i)]);
  }
  system_.size = part.system.dimension();
  system_.rhs = [this](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { ghosted_rhs(t, y, dydt); };
  system_.after_step = [this](double t, Eigen::VectorXd& y) { part.system.after_step(t, y); };
  system_.sparsity = [this] { return part.system.jacobian_pattern(); };
  system_.eliminable = eliminable_unknowns(part.system.layout());
  system_.describe = [this](Eigen::Index i) { return describe_unknown(part.system.model(), i); };
  RunOptions mine = o;
  mine.method = method;
  mine.threads = 1;  // the submodels themselves run side by side
  stepper_ = stepper_entry(method).make(system_, stepper_settings(mine));
}

void LoosePart::make_past(double t0, double H) {
  Eigen::VectorXd f0(part.system.dimension());
  part.system.rhs(t0, part.x[0], f0);  // own bodies exact: the ghosts are the true initial values
  for (int j = 1; j <= order_; ++j) part.x[static_cast<std::size_t>(j)] = part.x[0] - (j * H) * f0;
}

void LoosePart::start(double t0, double H) {
  const StateLayout& l = part.system.layout();
  for (std::size_t e = 0; e < history_.size(); ++e) {
    const std::vector<int>& to = part.sub->exchanges[e].to;
    for (int j = order_; j >= 0; --j) {
      Sample s{-j, t0 - j * H, std::vector<double>(to.size() * numbers)};
      partitioned::pack_bodies(l, part.x[static_cast<std::size_t>(j)], to, s.bodies.data());
      history_[e].push_front(std::move(s));
    }
  }
  publish(0, t0);
}

void LoosePart::extrapolate(std::size_t e, double t, const std::vector<int>& positions, std::vector<double>& out) const {
  const std::deque<Sample>& h = history_[e];
  double w[3];
  lagrange_weights(h, t, w);
  out.assign(positions.size() * numbers, 0.0);
  for (std::size_t j = 0; j < h.size(); ++j)
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const double* s = h[j].bodies.data() + static_cast<std::size_t>(positions[i]) * numbers;
      double* o = out.data() + i * numbers;
      for (int c = 0; c < numbers; ++c) o[c] += w[j] * s[c];
    }
}

void LoosePart::extrapolate_ghosts(double t, Eigen::VectorXd& y) {
  const StateLayout& l = part.system.layout();
  for (std::size_t e = 0; e < history_.size(); ++e) {
    extrapolate(e, t, ghost_at_[e], ghost_buffer_);
    partitioned::unpack_bodies(l, y, ghost_slots_[e], ghost_buffer_.data());
    for (int g : ghost_slots_[e]) y.segment<4>(l.orientation(g)).normalize();
  }
}

void LoosePart::reset_borrowed(long index) {
  const StateLayout& l = part.system.layout();
  for (std::size_t e = 0; e < history_.size(); ++e) {
    const Sample& newest = history_[e].front();
    if (newest.index != index) continue;
    const std::vector<int>& to = part.sub->exchanges[e].to;
    for (int i : borrowed_at_[e])
      partitioned::unpack_bodies(l, part.x[0], {to[static_cast<std::size_t>(i)]},
                                 newest.bodies.data() + static_cast<std::size_t>(i) * numbers);
  }
}

void LoosePart::integrate(double t0, double t1, const std::vector<std::pair<long, double>>& outputs) {
  const StepperStats before = stepper_->stats();
  stepper_->start(t0, part.x[0], t1);  // the ghosts moved on: what the method kept of f is stale
  std::size_t next = 0;
  auto keep = [&](bool last) {  // the snapshots up to the stepper's time
    while (next < outputs.size() && (last || at_or_before(outputs[next].second, stepper_->t()))) {
      const auto [index, t] = outputs[next++];
      Published s{index, t, {}};
      if (at_or_before(stepper_->t(), t)) {  // a step ends on it
        s.x = stepper_->y();
      } else {
        stepper_->dense(t, s.x);
        part.system.after_step(t, s.x);  // as a step's end: quaternions normalised, drivers imposed
      }
      snapshots_.push_back(std::move(s));
    }
  };
  while (!stepper_->done()) {
    stepper_->step();
    keep(false);
  }
  keep(true);
  part.x[0] = stepper_->y();
  const StepperStats& after = stepper_->stats();
  steps += after.accepted - before.accepted;
  rejected += after.rejected - before.rejected;
  evaluations += after.evaluations - before.evaluations;
}

void LoosePart::take_snapshot(long index, const StateLayout& global, Eigen::VectorXd& y) {
  if (snapshots_.empty() || snapshots_.front().index != index)
    throw RunError("internal: snapshot " + std::to_string(index) + " was not kept");
  partitioned::gather(part, snapshots_.front().x, global, y);
  snapshots_.pop_front();
}

namespace {
// The largest distances between the guesses (packed, one per near body) and the sample's
// near bodies.
CouplingError distance(const std::vector<double>& guess, const std::vector<int>& near, const double* packed) {
  CouplingError err;
  for (std::size_t i = 0; i < near.size(); ++i) {
    const double* g = guess.data() + i * numbers;
    const double* s = packed + static_cast<std::size_t>(near[i]) * numbers;
    const Eigen::Map<const Eigen::Vector3d> p(s), v(s + 7);
    err.position = std::max(err.position, (Eigen::Map<const Eigen::Vector3d>(g) - p).norm());
    err.velocity = std::max(err.velocity, (Eigen::Map<const Eigen::Vector3d>(g + 7) - v).norm());
  }
  return err;
}
}  // namespace

std::optional<CouplingError> LoosePart::prediction_error(std::size_t e, long index, const double* packed) const {
  for (const Sample& p : predicted_[e])
    if (p.index == index) return distance(p.bodies, part.sub->exchanges[e].near, packed);
  return std::nullopt;
}

void LoosePart::predict(long index, double t) {
  const StateLayout& l = part.system.layout();
  const int integrated = part.sub->integrated();
  for (std::size_t e = 0; e < predicted_.size(); ++e) {
    const Submodel::Exchange& x = part.sub->exchanges[e];
    Sample s{index, t, {}};
    extrapolate(e, t, x.near, s.bodies);
    for (std::size_t i = 0; i < x.near.size(); ++i) {
      const int slot = x.to[static_cast<std::size_t>(x.near[i])];
      if (slot < integrated) partitioned::pack_bodies(l, part.x[0], {slot}, s.bodies.data() + i * numbers);
    }
    predicted_[e].push_back(std::move(s));
  }
}

std::optional<CouplingError> LoosePart::take(std::size_t e, long index, double t, const double* packed) {
  const std::optional<CouplingError> err = prediction_error(e, index, packed);
  std::deque<Sample>& p = predicted_[e];
  while (!p.empty() && p.front().index <= index) p.pop_front();
  std::deque<Sample>& h = history_[e];
  Sample s = std::move(h.back());  // the oldest one goes (start() filled the history); its buffer is reused
  h.pop_back();
  s.index = index;
  s.t = t;
  std::copy(packed, packed + s.bodies.size(), s.bodies.begin());
  h.push_front(std::move(s));
  return err;
}

void LoosePart::publish(long index, double t) {
  std::lock_guard lock(board_mutex_);
  if (board_.size() >= retain_) {
    Published p = std::move(board_.front());  // reuses the oldest one's vector
    board_.pop_front();
    p.index = index;
    p.t = t;
    p.x = part.x[0];
    board_.push_back(std::move(p));
  } else {
    board_.push_back({index, t, part.x[0]});
  }
}

long LoosePart::published() const {
  std::lock_guard lock(board_mutex_);
  return board_.back().index;
}

double LoosePart::pack_published(long index, const std::vector<int>& bodies, double* out) const {
  std::lock_guard lock(board_mutex_);
  for (const Published& p : board_)
    if (p.index == index) {
      partitioned::pack_bodies(part.system.layout(), p.x, bodies, out);
      return p.t;
    }
  throw RunError("internal: macro-step end " + std::to_string(index) + " is no longer kept");
}

void LoosePart::save() {
  saved_ = part.x[0];
  saved_h_ = stepper_->next_step();
  saved_snapshots_ = snapshots_.size();
  saved_history_ = history_;
}

void LoosePart::restore(long index) {
  part.x[0] = saved_;
  stepper_->set_next_step(saved_h_);
  snapshots_.resize(saved_snapshots_);
  history_ = saved_history_;
  for (auto& p : predicted_)
    while (!p.empty() && p.back().index >= index) p.pop_back();
  std::lock_guard lock(board_mutex_);
  while (!board_.empty() && board_.back().index >= index) board_.pop_back();
}

namespace {
void save_samples(StateWriter& w, const auto& samples) {
  w.integer(static_cast<std::int64_t>(samples.size()));
  for (const auto& s : samples) {
    w.integer(s.index);
    w.real(s.t);
    w.vector(Eigen::Map<const Eigen::VectorXd>(s.bodies.data(), static_cast<Eigen::Index>(s.bodies.size())));
  }
}

// `size`: the numbers each sample has; at most `most` samples.
template <class Sample>
std::deque<Sample> restore_samples(StateReader& in, std::size_t size, std::size_t most) {
  std::deque<Sample> out(static_cast<std::size_t>(in.integer(0, static_cast<std::int64_t>(most))));
  for (Sample& s : out) {
    s.index = in.integer(INT64_MIN / 2, INT64_MAX / 2);
    s.t = in.real();
    const Eigen::VectorXd v = in.vector(static_cast<Eigen::Index>(size));
    s.bodies.assign(v.data(), v.data() + v.size());
  }
  return out;
}
}  // namespace

void LoosePart::save(StateWriter& w) const {
  if (!snapshots_.empty()) throw RunError("internal: a loose checkpoint with snapshots not yet taken");
  w.text("loose part");
  w.integer(steps);
  w.integer(rejected);
  w.integer(evaluations);
  w.vector(part.x[0]);
  for (std::size_t e = 0; e < history_.size(); ++e) {
    save_samples(w, history_[e]);
    save_samples(w, predicted_[e]);
  }
  std::lock_guard lock(board_mutex_);
  w.integer(static_cast<std::int64_t>(board_.size()));
  for (const Published& p : board_) {
    w.integer(p.index);
    w.real(p.t);
    w.vector(p.x);
  }
  stepper_->save(w);
}

void LoosePart::restore(StateReader& in) {
  in.expect("loose part");
  for (long* v : {&steps, &rejected, &evaluations}) *v = in.integer(0, INT64_MAX);
  const Eigen::Index n = part.system.dimension();
  part.x[0] = in.vector(n);
  const std::size_t most = 1u << 20;  // far more than any run keeps
  for (std::size_t e = 0; e < history_.size(); ++e) {
    const Submodel::Exchange& x = part.sub->exchanges[e];
    history_[e] = restore_samples<Sample>(in, x.to.size() * numbers, most);
    predicted_[e] = restore_samples<Sample>(in, x.near.size() * numbers, most);
    if (history_[e].size() != static_cast<std::size_t>(order_) + 1) in.fail("its neighbour samples are not of this run's extrapolation");
  }
  std::deque<Published> board(static_cast<std::size_t>(in.integer(1, static_cast<std::int64_t>(retain_))));
  for (Published& p : board) {
    p.index = in.integer(0, INT64_MAX);
    p.t = in.real();
    p.x = in.vector(n);
  }
  {
    std::lock_guard lock(board_mutex_);
    board_ = std::move(board);
  }
  snapshots_.clear();
  // The method's state goes over a started one (which sizes it), at the state's time.
  stepper_->start(board_.back().t, part.x[0], o_.t_end);
  stepper_->restore(in);
}

void MacroGrid::save(StateWriter& w) const {
  w.integer(base_);
  w.integer(static_cast<std::int64_t>(ends_.size()));
  for (double t : ends_) w.real(t);
}

void MacroGrid::restore(StateReader& in) {
  base_ = in.integer(0, INT64_MAX / 2);
  ends_.resize(static_cast<std::size_t>(in.integer(1, 1 << 20)));
  for (double& t : ends_) t = in.real();
}

MacroGrid::MacroGrid(const RunOptions& o, double H) : o_(o), H_(H), grid_(step_grid(o.t_start, o.t_end, o.step)) {
  // An output interval that is not a whole number of steps (adaptive methods) is rounded onto the grid.
  every_ = std::max(1, output_steps(o));
  outputs_ = (grid_.steps + every_ - 1) / every_;
  ends_.push_back(o.t_start);
}

void MacroGrid::extend(long m) {
  while (last() < m && !complete()) add(last(), H_);
}

void MacroGrid::add(long m, double H) {
  while (last() > m) ends_.pop_back();
  const double t = end(m) + H;
  ends_.push_back(t >= grid_.t_end - 1e-12 * std::max(1.0, std::abs(grid_.t_end)) ? grid_.t_end : t);
}

void MacroGrid::forget_before(long m) {
  while (base_ < m && ends_.size() > 1) {
    ends_.pop_front();
    ++base_;
  }
}

int MacroGrid::steps_per_run() const {
  if (!(H_ > 0.0)) return 1;
  const double per_output = output_dt(o_) / H_;
  return static_cast<int>(std::clamp(std::ceil(per_output - 1e-9) + 1.0, 1.0, 64.0));
}

std::vector<std::pair<long, double>> MacroGrid::outputs_in(double t0, double t1) const {
  std::vector<std::pair<long, double>> out;
  const double span = static_cast<double>(every_) * grid_.h;
  long k = std::max(1L, static_cast<long>(std::floor((t0 - grid_.t_start) / span)) - 1);
  while (k > 1 && !at_or_before(output_time(k - 1), t0)) --k;
  for (; k <= outputs_; ++k) {
    const double t = output_time(k);
    if (at_or_before(t, t0)) continue;
    if (!at_or_before(t, t1)) break;
    out.emplace_back(k, t);
  }
  return out;
}

}  // namespace mbsflow::loose
