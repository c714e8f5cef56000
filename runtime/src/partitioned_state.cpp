#include "partitioned_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mbsflow/methods/dopri5.hpp"
#include "mbsflow/methods/rk4.hpp"

namespace mbsflow::partitioned {
namespace {

void copy_body(const StateLayout& from_layout, const Eigen::VectorXd& from, Eigen::Index i, const StateLayout& to_layout,
               Eigen::VectorXd& to, Eigen::Index j) {
  to.segment<3>(to_layout.position(j)) = from.segment<3>(from_layout.position(i));
  to.segment<4>(to_layout.orientation(j)) = from.segment<4>(from_layout.orientation(i));
  to.segment<3>(to_layout.velocity(j)) = from.segment<3>(from_layout.velocity(i));
  to.segment<3>(to_layout.angular_velocity(j)) = from.segment<3>(from_layout.angular_velocity(i));
}

}  // namespace

Part::Part(const Model& model, const Submodel& s, int stages, bool fold)
    : Part(std::make_shared<Model>(submodel_model(model, s)), s, stages, fold) {
  const std::vector<Eigen::Index> at = flexible_tail_offsets(model.flexible);
  global = {static_cast<Eigen::Index>(model.bodies.size()), at.back()};
  for (std::size_t i = 0; i < s.flexible.size(); ++i) {
    const auto f = static_cast<std::size_t>(s.flexible[i]);
    tails.push_back({system.flexible_state(i), global.tail(at[f]), at[f + 1] - at[f], system.model().flexible[i].frame});
  }
}

Part::Part(std::shared_ptr<Model> local, const Submodel& s, int stages, bool fold)
    : sub(&s), system(local, s.integrated()), own(static_cast<Eigen::Index>(s.own.size())),
      rk4_folded(fold && stages == 4 && s.borrowed.empty()) {
  Eigen::VectorXd y0 = system.initial_state();  // its errors name joints
  const auto n_own = static_cast<int>(own);
  // Clusters of borrowed bodies (loose coupling's overlap) have local indices past the own ones.
  std::vector<char> edge(static_cast<std::size_t>(s.integrated()), 0);
  const std::vector<Joint>& joints = system.model().joints;
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const int a = joints[k].body1, b = joints[k].body2;  // local; ground is -1
    if (a >= n_own || b >= n_own) {
      ghost_joints.push_back(static_cast<int>(k));
      for (int i : {a, b})
        if (i >= 0 && i < n_own) edge[static_cast<std::size_t>(i)] = 1;
    } else {
      inner_joints.push_back(static_cast<int>(k));
    }
  }
  // A rigid cluster is solved as a whole: one edge body makes all of it edge.
  for (int c = 0; c < system.clusters(); ++c) {
    const std::vector<int>& bodies = system.cluster_bodies(c);
    if (std::any_of(bodies.begin(), bodies.end(), [&](int i) { return edge[static_cast<std::size_t>(i)] != 0; }))
      for (int i : bodies) edge[static_cast<std::size_t>(i)] = 1;
  }
  // So is a flexible body (only its frame may be joined to a ghost: uncut_pieces).
  for (const FlexibleBody& f : system.model().flexible)
    if (edge[static_cast<std::size_t>(f.frame)])
      for (int i : f.nodes) edge[static_cast<std::size_t>(i)] = 1;
  for (int i = 0; i < n_own; ++i) {
    own_bodies.push_back(i);
    (edge[static_cast<std::size_t>(i)] ? edge_bodies : inner_bodies).push_back(i);
  }
  for (int i = n_own; i < static_cast<int>(system.layout().bodies); ++i) ghost_bodies.push_back(i);
  // The system shares `local` (made here, not const): its joints are compiled and read no
  // more (the Jacobian's pattern comes from the compiled joints). The submodels of a
  // 10^6-body chain held 256 MB of them.
  std::vector<Joint>().swap(local->joints);
  // The stage vectors after that, so that the joints' records and these are never held together.
  x.assign(static_cast<std::size_t>(rk4_folded ? 3 : stages), y0);
  k.assign(static_cast<std::size_t>(rk4_folded ? 2 : stages), Eigen::VectorXd::Zero(system.dimension()));
}

void copy_ghosts(const StateLayout& owner_layout, const Eigen::VectorXd& from, const Submodel::Exchange& e, Part& me, int s) {
  for (std::size_t i = 0; i < e.from.size(); ++i)
    copy_body(owner_layout, from, e.from[i], me.system.layout(), me.input(s), e.to[i]);
}

void copy_ghosts(const Part& owner, const Submodel::Exchange& e, Part& me, int s) {
  copy_ghosts(owner.system.layout(), owner.input(s), e, me, s);
}

void copy_local_ghosts(const std::vector<Part*>& parts, std::size_t p, int s) {
  for (const Submodel::Exchange& e : parts[p]->sub->exchanges)
    if (const Part* owner = parts[static_cast<std::size_t>(e.neighbour)]) copy_ghosts(*owner, e, *parts[p], s);
}

namespace {
// Own field block `block` (for_own_blocks' order), v, into its places in the global state
// out: what own_elements lists, computed rather than held (8 bytes per number).
void to_global(const Part& part, int block, const Eigen::VectorXd& v, Eigen::VectorXd& out) {
  if (block >= 4) {
    const Part::Tail& t = part.tails[static_cast<std::size_t>(block - 4)];
    out.segment(t.global, t.size) = v;
    return;
  }
  const StateLayout& global = part.global;
  const StateField& field = state_fields[block];
  for (Eigen::Index b = 0; b < part.own; ++b) {
    const Eigen::Index at = (global.*field.offset)(part.sub->own[static_cast<std::size_t>(b)]);
    for (int c = 0; c < field.width; ++c) out[at + c] = v[field.width * b + c];
  }
}
}  // namespace

void StateShare::add(const Decomposition& d, const Submodel& s) {
  bodies.insert(bodies.end(), s.own.begin(), s.own.end());
  const StateLayout global = d.layout();
  for (int f : s.flexible) {
    const auto i = static_cast<std::size_t>(f);
    tails.push_back({global.tail(d.flexible_tail[i]), d.flexible_tail[i + 1] - d.flexible_tail[i]});
  }
}

std::size_t StateShare::numbers() const {
  std::size_t n = bodies.size() * body_numbers;
  for (const Span& t : tails) n += static_cast<std::size_t>(t.size);
  return n;
}

void pack_share(const StateLayout& global, const Eigen::VectorXd& y, const StateShare& share, void* out) {
  pack_bodies(global, y, share.bodies, out);
  auto* at = static_cast<unsigned char*>(out) + share.bodies.size() * body_numbers * sizeof(double);
  for (const StateShare::Span& t : share.tails) {
    std::memcpy(at, y.data() + t.at, sizeof(double) * static_cast<std::size_t>(t.size));
    at += sizeof(double) * static_cast<std::size_t>(t.size);
  }
}

void unpack_share(const StateLayout& global, Eigen::VectorXd& y, const StateShare& share, const void* in) {
  unpack_bodies(global, y, share.bodies, in);
  const auto* at = static_cast<const unsigned char*>(in) + share.bodies.size() * body_numbers * sizeof(double);
  for (const StateShare::Span& t : share.tails) {
    std::memcpy(y.data() + t.at, at, sizeof(double) * static_cast<std::size_t>(t.size));
    at += sizeof(double) * static_cast<std::size_t>(t.size);
  }
}

std::vector<Eigen::Index> own_elements(const Decomposition& d, std::size_t q) {
  const Submodel& sub = d.submodels[q];
  const StateLayout global = d.layout();
  std::vector<Eigen::Index> out;
  out.reserve(sub.own.size() * body_numbers);
  for (const StateField& f : state_fields)
    for (int body : sub.own)
      for (int c = 0; c < f.width; ++c) out.push_back((global.*f.offset)(body) + c);
  StateShare tails;
  tails.add(d, sub);
  for (const StateShare::Span& t : tails.tails)
    for (Eigen::Index i = 0; i < t.size; ++i) out.push_back(t.at + i);
  return out;
}

// Through memcpy: a message buffer need not be aligned for doubles.
void pack_bodies(const StateLayout& l, const Eigen::VectorXd& x, const std::vector<int>& bodies, void* buffer) {
  auto* out = static_cast<unsigned char*>(buffer);
  auto put = [&](Eigen::Index at, int n, int to) {
    std::memcpy(out + to * sizeof(double), x.data() + at, sizeof(double) * static_cast<std::size_t>(n));
  };
  for (int i : bodies) {
    put(l.position(i), 3, 0);
    put(l.orientation(i), 4, 3);
    put(l.velocity(i), 3, 7);
    put(l.angular_velocity(i), 3, 10);
    out += body_numbers * sizeof(double);
  }
}

void unpack_bodies(const StateLayout& l, Eigen::VectorXd& x, const std::vector<int>& bodies, const void* buffer) {
  const auto* in = static_cast<const unsigned char*>(buffer);
  auto get = [&](Eigen::Index at, int n, int from) {
    std::memcpy(x.data() + at, in + from * sizeof(double), sizeof(double) * static_cast<std::size_t>(n));
  };
  for (int i : bodies) {
    get(l.position(i), 3, 0);
    get(l.orientation(i), 4, 3);
    get(l.velocity(i), 3, 7);
    get(l.angular_velocity(i), 3, 10);
    in += body_numbers * sizeof(double);
  }
}

namespace {

// RK4's update of stage s on the entries [at, at + n) of own bodies: the next stage input,
// or after stage 3 the new state (before renormalisation).
void rk4_update_entries(Part& part, int s, double h, Eigen::Index at, Eigen::Index n) {
  auto seg = [&](Eigen::VectorXd& v) { return v.segment(at, n); };
  if (s < 3) {
    rk4::stage_input(seg(part.x[0]), seg(part.derivative(s)), h, s, seg(part.input(s + 1)));
    if (part.rk4_folded && s > 0) rk4::accumulate(seg(part.derivative(0)), seg(part.derivative(s)));
  } else if (part.rk4_folded) {
    rk4::finish(seg(part.x[0]), seg(part.derivative(0)), seg(part.derivative(3)), h);
  } else {
    rk4::combine(seg(part.x[0]), seg(part.k[0]), seg(part.k[1]), seg(part.k[2]), seg(part.k[3]), h);
  }
}

}  // namespace

void rk4_stage(Part& part, int s, double t, double t_next) {
  const double h = t_next - t;
  part.system.rhs(t + rk4::stage_fraction[s] * h, part.input(s), part.derivative(s));
  for_own_blocks(part, [&](Eigen::Index at, Eigen::Index n) { rk4_update_entries(part, s, h, at, n); });
  if (s == 3) part.system.after_step(t_next, part.x[0]);
}

namespace {

// Calls f(offset, length) for each field block of each run of consecutive listed bodies
// (the layout keeps each field of consecutive bodies together).
template <class F>
void for_bodies(const Part& part, const std::vector<int>& bodies, F f) {
  const StateLayout& l = part.system.layout();
  for_body_runs(bodies.data(), bodies.size(), [&](Eigen::Index first, Eigen::Index n) {
    f(l.position(first), 3 * n);
    f(l.orientation(first), 4 * n);
    f(l.velocity(first), 3 * n);
    f(l.angular_velocity(first), 3 * n);
  });
}

// The stage update of rk4_stage, for some own bodies (whole flexible bodies, their modes
// with their frame): the next stage input, or after stage 3 the new state (renormalised,
// drivers imposed).
void rk4_update(Part& part, const std::vector<int>& bodies, int s, double h, double t_next) {
  for_bodies(part, bodies, [&](Eigen::Index at, Eigen::Index n) { rk4_update_entries(part, s, h, at, n); });
  for (const Part::Tail& t : part.tails)
    if (std::binary_search(bodies.begin(), bodies.end(), t.frame)) rk4_update_entries(part, s, h, t.local, t.size);
  if (s == 3) part.system.after_step_of(t_next, part.x[0], bodies);
}

// Half of rk4_stage: kinematics of `moved`, forces of `joints`, derivatives and stage
// update of `bodies`.
void rk4_half(Part& part, int s, double t, double t_next, const std::vector<int>& moved, const std::vector<int>& joints,
              const std::vector<int>& bodies) {
  const double h = t_next - t, ts = t + rk4::stage_fraction[s] * h;
  part.system.kinematics_of(ts, part.input(s), moved);
  part.system.joint_forces_of(joints);
  part.system.derivatives_of(ts, part.input(s), part.derivative(s), bodies);
  rk4_update(part, bodies, s, h, t_next);
}

}  // namespace

void rk4_inner_stage(Part& part, int s, double t, double t_next) {
  rk4_half(part, s, t, t_next, part.own_bodies, part.inner_joints, part.inner_bodies);
}

void rk4_edge_stage(Part& part, int s, double t, double t_next) {
  rk4_half(part, s, t, t_next, part.ghost_bodies, part.ghost_joints, part.edge_bodies);
}

void dopri5_stage(Part& part, int s, double t, double h, bool need_k0, double atol, double rtol,
                  Eigen::VectorXd& squares) {
  const auto i = static_cast<std::size_t>(s);
  if (s > 0 || need_k0) part.system.rhs(t + dopri5::c[s] * h, part.x[i], part.k[i]);
  int block = 0;
  for_own_blocks(part, [&](Eigen::Index at, Eigen::Index n) {
    auto k = [&](int j) { return part.k[static_cast<std::size_t>(j)].segment(at, n); };
    if (s < 6) {
      dopri5::stage_input(s + 1, part.x[0].segment(at, n), k, h, part.x[i + 1].segment(at, n));
      return;
    }
    Eigen::VectorXd sq(n);
    dopri5::error_squares(part.x[0].segment(at, n), part.x[6].segment(at, n), k, h, atol, rtol, sq);
    to_global(part, block++, sq, squares);
  });
}

void dopri5_accept(Part& part, double h, double t_new) {
  part.r.resize(5, Eigen::VectorXd::Zero(part.system.dimension()));
  for_own_blocks(part, [&](Eigen::Index at, Eigen::Index n) {
    auto k = [&](int j) { return part.k[static_cast<std::size_t>(j)].segment(at, n); };
    auto r = [&](int j) { return part.r[static_cast<std::size_t>(j)].segment(at, n); };
    dopri5::dense_setup(part.x[0].segment(at, n), part.x[6].segment(at, n), k, h, r);
    part.x[0].segment(at, n) = part.x[6].segment(at, n);
  });
  part.system.after_step(t_new, part.x[0]);
}

void dopri5_dense(const Part& part, double theta, Eigen::VectorXd& out) {
  int block = 0;
  for_own_blocks(part, [&](Eigen::Index at, Eigen::Index n) {
    Eigen::VectorXd v(n);
    dopri5::dense_eval([&](int j) { return part.r[static_cast<std::size_t>(j)].segment(at, n); }, theta, v);
    to_global(part, block++, v, out);
  });
}

void gather(const Part& p, const Eigen::VectorXd& local, const StateLayout& global, Eigen::VectorXd& y) {
  for (Eigen::Index i = 0; i < p.own; ++i) copy_body(p.system.layout(), local, i, global, y, p.sub->own[static_cast<std::size_t>(i)]);
  for (const Part::Tail& t : p.tails) y.segment(t.global, t.size) = local.segment(t.local, t.size);
}

void gather(const Part& p, const StateLayout& global, Eigen::VectorXd& y) { gather(p, p.x[0], global, y); }

void scatter(const Eigen::VectorXd& y, const StateLayout& global, Part& p) {
  Eigen::Index i = 0;
  for (const std::vector<int>* bodies : {&p.sub->own, &p.sub->borrowed, &p.sub->ghosts})
    for (int b : *bodies) copy_body(global, y, b, p.system.layout(), p.x[0], i++);
  for (const Part::Tail& t : p.tails) p.x[0].segment(t.local, t.size) = y.segment(t.global, t.size);
}

void gather(const std::vector<Part>& parts, const StateLayout& global, Eigen::VectorXd& y) {
  y.resize(global.size());
  for (const Part& p : parts) gather(p, global, y);
}

std::optional<Divergence> check(const Part& p) {
  auto d = find_divergence(p.system.layout(), p.x[0], p.own);  // own bodies come first
  if (d) d->body = p.sub->own[static_cast<std::size_t>(d->body)];
  return d;
}

std::optional<Divergence> check(const std::vector<Part>& parts) {
  std::optional<Divergence> first;
  for (const Part& p : parts)
    if (auto d = check(p); d && (!first || d->body < first->body)) first = d;
  return first;
}

}  // namespace mbsflow::partitioned
