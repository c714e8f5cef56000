#include "mbsflow/analysis/equilibrium.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <Eigen/Geometry>
#include <limits>

#include "arc_step.hpp"
#include "constrained.hpp"
#include "mbsflow/analysis/linearization.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/klu_lu.hpp"

namespace mbsflow {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
constexpr double max_turn = 1.0;  // rad per iteration and body

// The largest force or torque on one body.
double worst(const Eigen::VectorXd& f, Eigen::Index* at = nullptr) {
  Eigen::Index i = 0;
  const double w = f.size() ? f.cwiseAbs().maxCoeff(&i) : 0.0;
  if (at) *at = i;
  return w;
}

// Solves [S C^T; C 0] [dx; mu] = [f; 0], S = K + M / h^2: the step on the allowed motions.
// The pattern is the same at every iteration: analysed once (AMD on a million rows takes
// longer than the factorisation).
struct Factor {
  KluLu<double> lu;
  std::vector<int> outer, inner;  // the pattern analysed
  Sparse a;                       // the matrix factored last: its storage serves the next
};

// a = k + s m where m's entries lie within k's pattern (the bodies' mass blocks within
// their own stiffness blocks): k's values copied into a's storage, kept from one
// iteration to the next, and s m added in place (Eigen's sum makes a fresh matrix each
// time, 130 MB at 100 000 bodies). False where m has an entry outside k's pattern.
bool add_within(const Sparse& k, const Sparse& m, double s, Sparse& a) {
  a = k;
  for (Eigen::Index c = 0; c < m.outerSize(); ++c) {
    Sparse::InnerIterator at(a, c);
    for (Sparse::InnerIterator it(m, c); it; ++it) {
      while (at && at.row() < it.row()) ++at;
      if (!at || at.row() != it.row()) return false;
      at.valueRef() += s * it.value();
    }
  }
  return true;
}

Eigen::VectorXd step(const LinearModel& lm, const Eigen::VectorXd& f, double h, Factor& factor) {
  const Eigen::Index n = lm.size(), r = lm.C.rows();
  // Redundant rows (a planar loop in 3D) make the augmented matrix singular: a tiny
  // negative diagonal on the multipliers keeps it regular and leaves dx as it is.
  const double eps = 1e-12 * (lm.M.coeffs().size() ? lm.M.coeffs().cwiseAbs().maxCoeff() : 1.0) / (h * h);
  Sparse& a = factor.a;
  if (r > 0 || !add_within(lm.K, lm.M, 1.0 / (h * h), a)) {
    a = lm.K + (1.0 / (h * h)) * lm.M;
    augment(a, lm.C, -eps);
  }
  // Compared in place: a copy of the pattern at every iteration would cost as much as the
  // comparison (tens of MB for 100 000 bodies).
  const auto outer = a.outerIndexPtr(), inner = a.innerIndexPtr();
  const auto outer_count = static_cast<std::size_t>(a.outerSize() + 1), inner_count = static_cast<std::size_t>(a.nonZeros());
  if (!std::equal(outer, outer + outer_count, factor.outer.begin(), factor.outer.end()) ||
      !std::equal(inner, inner + inner_count, factor.inner.begin(), factor.inner.end())) {
    factor.lu.analyze(a);
    factor.outer.assign(outer, outer + outer_count);
    factor.inner.assign(inner, inner + inner_count);
  }
  factor.lu.factorize(a);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n + r);
  rhs.head(n) = f;
  factor.lu.solve(rhs);
  return rhs.head(n);
}

// The rigid joints' largest gap (m or rad) on the rows that hold free bodies.
double joint_gap(const MultibodySystem& sys, double t, const LinearModel& lm, const Eigen::VectorXd& y) {
  if (lm.constraint_row.empty()) return 0.0;
  const Eigen::VectorXd values = sys.constraint_values(t, y);
  double gap = 0.0;
  for (const Eigen::Index row : lm.constraint_row) gap = std::max(gap, std::abs(values[row]));
  return gap;
}

// Moves y back onto the rigid joints after a step: Newton on the joints' values phi with
// the step's own factors, [S C^T; C 0] [dx; mu] = [0; -phi], so that the move is the
// least in S = K + M / h^2. The mass-weighted projection of after_step alone would move a
// stiff part's modes (or a beam's nodes) by the joints' second-order drift, which the
// stiffness turns into forces far above the residual (the bar of examples/fe on its
// pivot: 1e5 N of axial force from 1e-5 m), and every Newton step would be spent on them.
void settle_on_joints(const MultibodySystem& sys, double t, const LinearModel& lm, const Factor& factor, Eigen::VectorXd& y) {
  const Eigen::Index n = lm.size(), r = lm.C.rows();
  if (r == 0 || static_cast<Eigen::Index>(lm.constraint_row.size()) != r) return;
  // The factors are the step's start's, so the iteration converges linearly, at a rate
  // about the step's turn: a few tens of iterations at most, each a constraint evaluation
  // and a solve.
  double last = std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Eigen::VectorXd values = sys.constraint_values(t, y);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n + r);
    double worst = 0.0;
    for (Eigen::Index k = 0; k < r; ++k) {
      rhs[n + k] = -values[lm.constraint_row[static_cast<std::size_t>(k)]];
      worst = std::max(worst, std::abs(rhs[n + k]));
    }
    if (worst <= 1e-12 || worst > 0.5 * last) return;  // on the joints, or no longer closing in
    last = worst;
    factor.lu.solve(rhs);
    apply_tangent_step(sys.layout(), lm.coords, rhs.head(n), y);
  }
}

// The potential energy the steps lower: gravity, the elastic energy, and the loads' (a
// dead force F at a body point p has -F . p; torques and forces in the body frame have no
// potential and are left to the residual test).
double potential(MultibodySystem& sys, double t, const Eigen::VectorXd& y) {
  const Energy e = sys.energy(t, y);
  double loads = 0.0;
  const StateLayout& l = sys.layout();
  for (const Load& load : sys.model().loads) {
    if (load.body_frame) continue;
    const auto q = y.segment<4>(l.orientation(load.body));
    const Eigen::Vector3d at = y.segment<3>(l.position(load.body)) +
                               Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized() *
                                   Eigen::Vector3d(load.point[0], load.point[1], load.point[2]);
    loads -= evaluate(load.function, t).value * Eigen::Vector3d(load.force[0], load.force[1], load.force[2]).dot(at);
  }
  return e.gravity + e.elastic + loads;
}

// Whether the residual is minus the gradient of `potential`: not where a driven body moves
// (a bushing's damping against it pushes at rest), a load is a torque or follows its body,
// or a motor applies an effort, none of which has a potential there.
bool residual_has_potential(const Model& m, const StateLayout& l, const Eigen::VectorXd& y) {
  for (const Load& load : m.loads)
    if (load.body_frame || load.torque != Vec3{}) return false;
  for (const Driver& d : m.drivers)
    if (y.segment<3>(l.velocity(d.body)).squaredNorm() + y.segment<3>(l.angular_velocity(d.body)).squaredNorm() > 0.0) return false;
  for (const Joint& j : m.joints)
    if (j.motor->kind == JointMotor::Kind::effort) return false;
  return true;
}

}  // namespace

Equilibrium find_equilibrium(MultibodySystem& sys, double t, const Eigen::VectorXd& start, const EquilibriumOptions& o) {
  const StateLayout& l = sys.layout();
  const FreeCoordinates coords = free_coordinates(sys);
  const std::vector<int>& bodies = coords.bodies;
  Eigen::VectorXd y = start;
  set_at_rest(l, coords, y);
  sys.after_step(t, y);  // on the rigid joints and the drivers' motion
  Equilibrium out;
  Eigen::VectorXd f = static_residual(sys, t, y, coords);
  out.initial_residual = worst(f);
  // The scale of "balanced": the weight the supports carry (the largest force a joint of
  // a hanging chain transmits), or the forces at the start; a residual of 1e-9 of it is
  // at rounding's level for a long chain.
  const Model& m = sys.model();
  const double g = std::sqrt(m.gravity[0] * m.gravity[0] + m.gravity[1] * m.gravity[1] + m.gravity[2] * m.gravity[2]);
  double weight = 0.0, extent = 0.0;
  for (int b : bodies) weight += m.bodies[static_cast<std::size_t>(b)].mass * g;
  for (int b : bodies) extent = std::max(extent, y.segment<3>(l.position(b)).norm());
  const double scale = std::max({weight, out.initial_residual, 1e-300});
  const double enough = o.tolerance * scale;
  double energy = potential(sys, t, y);
  // The first pseudo-time step moves the body with the largest acceleration by about a
  // hundredth of the model's size.
  double h = 1e-2;
  {
    double fastest = 0.0;
    for (std::size_t k = 0; k < bodies.size(); ++k)
      fastest = std::max(fastest, f.segment<3>(coords.start[k]).norm() /
                                      m.bodies[static_cast<std::size_t>(bodies[k])].mass);
    if (fastest > 0.0) h = std::sqrt(0.01 * std::max(extent, 1e-3) / fastest);
  }
  int iteration = 0;
  const ArcStep arcs(m, coords);
  const bool has_potential = residual_has_potential(m, l, y);
  Factor factor;
  LinearModel lm;
  bool linearized = false;  // lm is y's
  Sparse jacobian;  // the analytic Jacobian's pattern, made by the first linearisation, reused by every one
  // Stiff elements (a steel beam's axial stiffness, 1e8 N/m and more) leave a residual of
  // their stiffness times the positions' rounding, which may exceed `enough`: a residual
  // below 1e-6 of the scale that four iterations in a row have not halved is converged.
  double best = worst(f);
  int stalled = 0;
  while (worst(f) > enough && !(stalled >= 4 && worst(f) <= 1e-6 * scale)) {
    // Counted only below that level: a long chain released level raises its residual a
    // hundredfold while it falls, which is no stall.
    if (worst(f) < 0.5 * best) {
      best = worst(f);
      stalled = 0;
    } else if (worst(f) <= 1e-6 * scale) {
      ++stalled;
    } else {
      stalled = 0;
    }
    if (++iteration > o.max_iterations) {
      Eigen::Index at = 0;
      const double left = worst(f, &at);
      const std::size_t k = coords.body_of(at);
      const int body = bodies[k];
      const Eigen::Index e = at - coords.start[k];
      char buf[256];
      std::snprintf(buf, sizeof buf, "%s %.3g %s after %d iterations (the start had %.3g)",
                    e < 3 ? "a force of" : e < 6 ? "a torque of" : "a modal force of", left, e < 3 ? "N" : e < 6 ? "N m" : "N sqrt(kg)",
                    o.max_iterations, out.initial_residual);
      throw RunError("no static equilibrium found: body '" + m.bodies[static_cast<std::size_t>(body)].name +
                     "' does not settle, " + buf +
                     " (is it held against gravity and its loads? --at-initial linearises where it is)");
    }
    // A rejected step leaves y where it was: its linearisation serves the next try.
    if (!linearized) linearize_into(lm, sys, t, y, &jacobian, false);  // no damping: at rest
    linearized = true;
    Eigen::VectorXd dx;
    try {
      dx = step(lm, f, h, factor);
    } catch (const RunError&) {  // singular: a smaller pseudo-time step adds more mass
      h *= 0.25;
      continue;
    }
    // S dx = f gives f . dx = dx . S dx: not positive where S = K + M / h^2 is indefinite
    // along the step, which then climbs the potential towards a maximum or a saddle (a
    // pendulum released above level, Newton's step once h is long, heads for standing
    // upright, and the residual test below takes it). More of the mass term makes S
    // definite again. Where the residual has no potential, f . dx says nothing of the kind
    // (a train's bogies against wheelsets driven at 30 m/s: the Newton step that settles
    // them has f . dx < 0).
    if (has_potential && !(f.dot(dx) > 0.0)) {
      h *= 0.25;
      continue;
    }
    // No body turns by more than a radian in one step: a long step could turn a joint past
    // half a turn, where its rotational deflection jumps (and no equilibrium is near).
    double turn = 0.0;
    for (std::size_t k = 0; k < bodies.size(); ++k) turn = std::max(turn, dx.segment<3>(coords.start[k] + 3).norm());
    const double cut = std::min(1.0, max_turn / turn);
    dx *= cut;
    // The step, then up to two of its halves (a residual each, far cheaper than a new
    // factorisation): a step cut to the turn limit stays the same for every h above some
    // value, so shrinking h alone would factorise again and again for the same step.
    Eigen::VectorXd next, f_next;
    double e_next = 0.0;
    bool taken = false;
    Eigen::VectorXd applied;  // the step tried last: the one taken
    for (int half = 0; half < 3 && !taken; ++half, dx *= 0.5) {
      applied = dx;
      next = y;
      arcs.apply(l, dx, next);  // each body turned about where its bushings hold it
      settle_on_joints(sys, t, lm, factor, next);
      sys.after_step(t, next);
      f_next = static_residual(sys, t, next, coords);
      e_next = potential(sys, t, next);
      const bool lower = e_next <= energy + 1e-12 * (std::abs(energy) + scale * std::max(extent, 1.0));
      // A step the joints could not follow (a long turn of a chain on revolute joints) left
      // them open: its energy is not the model's, and the step is no step. after_step's
      // projection closes them to 1e-10 (m or rad) wherever it converges, so the bound
      // only catches where it did not.
      const bool closed = joint_gap(sys, t, lm, next) <= 1e-9 * std::max(extent, 1.0);
      taken = (lower || worst(f_next) < worst(f)) && f_next.allFinite() && closed;
      if (taken && half > 0) h *= 0.5;  // a shorter step fitted: the next starts from there
    }
    if (!taken) {
      h *= 0.25;  // the step overshot: more of the mass term
      continue;
    }
    // A step that lowered the energy (or the residual) lets the next one be longer: h
    // grows by 4 to 8, fastest where the residual falls, and the step becomes Newton's
    // (growing by 2 at least took a third more iterations over twenty models, from a
    // pendulum to 1000 random bodies, once the steps followed arcs). Unless the
    // potential fell by far less than the step's quadratic model f.dx - dx.K.dx / 2 said
    // and the residual did not halve: then K + M / h^2 is near singular or indefinite along
    // the step (a part on a spherical pivot released exactly level has no stiffness in two
    // directions there), its solution is mostly that direction, cut to the turn limit, and
    // a longer h would only make it more so: h shrinks instead (a trust region's rule).
    // A step cut to the turn limit says only that the limit, not h, bounded it (a long
    // chain released level: its first Newton steps would turn a link by hundreds of
    // radians): h stays, and grows once a step fits within the limit. Growing h on cut
    // steps keeps stepping along directions cut by 100x and more (three times the
    // iterations on a 10 000-link chain released level); shrinking it by the root of the
    // cut (so that a mass-ruled step, growing as h^2, would just fit) made the next
    // step's direction more the mass term's and less Newton's: 21 iterations in place of
    // 17 on a 100 000-link chain released level, 17 in place of 15 at 10 000 links, the
    // same or one more on the test suite's models.
    const double predicted = f.dot(applied) - 0.5 * applied.dot(lm.K * applied);
    if (energy - e_next < 0.25 * std::max(predicted, 0.0) && worst(f_next) > 0.5 * worst(f)) {
      h *= 0.5;
    } else if (cut < 1.0) {
      // h stays
    } else {
      h *= std::clamp(std::sqrt(worst(f) / std::max(worst(f_next), 1e-300)), 4.0, 8.0);
    }
    y = next;
    f = f_next;
    energy = e_next;
    linearized = false;
    if (o.progress) o.progress(iteration, worst(f));
  }
  out.state = y;
  out.jacobian.swap(jacobian);  // Eigen 3.4's SparseMatrix has no move: a "move" copies
  out.iterations = iteration;
  out.residual = worst(f);
  return out;
}

}  // namespace mbsflow
