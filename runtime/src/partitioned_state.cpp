#include "partitioned_state.hpp"

#include <cmath>

#include "mbsflow/methods/rk4.hpp"

namespace mbsflow::partitioned {
namespace {

// The four field blocks (position, orientation, velocity, angular velocity) of a layout:
// own bodies are the first `own` entries of each block.
template <class F>
void for_own_blocks(const StateLayout& l, Eigen::Index own, F f) {
  f(l.position(0), 3 * own);
  f(l.orientation(0), 4 * own);
  f(l.velocity(0), 3 * own);
  f(l.angular_velocity(0), 3 * own);
}

void copy_body(const StateLayout& from_layout, const Eigen::VectorXd& from, Eigen::Index i, const StateLayout& to_layout,
               Eigen::VectorXd& to, Eigen::Index j) {
  to.segment<3>(to_layout.position(j)) = from.segment<3>(from_layout.position(i));
  to.segment<4>(to_layout.orientation(j)) = from.segment<4>(from_layout.orientation(i));
  to.segment<3>(to_layout.velocity(j)) = from.segment<3>(from_layout.velocity(i));
  to.segment<3>(to_layout.angular_velocity(j)) = from.segment<3>(from_layout.angular_velocity(i));
}

}  // namespace

Part::Part(const Model& model, const Submodel& s)
    : sub(&s), system(submodel_model(model, s), static_cast<int>(s.own.size())), own(static_cast<Eigen::Index>(s.own.size())) {
  x[0] = system.initial_state();
  for (int i = 1; i < 4; ++i) x[i] = x[0];
  for (auto& v : k) v = Eigen::VectorXd::Zero(system.dimension());
}

void pull_ghosts(std::vector<Part>& parts, std::size_t p, int s) {
  Part& me = parts[p];
  for (const Submodel::Exchange& e : me.sub->exchanges) {
    const Part& owner = parts[static_cast<std::size_t>(e.neighbour)];
    for (std::size_t i = 0; i < e.from.size(); ++i)
      copy_body(owner.system.layout(), owner.x[s], e.from[i], me.system.layout(), me.x[s], e.to[i]);
  }
}

void stage(Part& part, int s, double t, double t_next) {
  const double h = t_next - t;
  part.system.rhs(t + rk4::stage_fraction[s] * h, part.x[s], part.k[s]);
  const StateLayout& l = part.system.layout();
  if (s < 3) {
    for_own_blocks(l, part.own, [&](Eigen::Index at, Eigen::Index n) {
      rk4::stage_input(part.x[0].segment(at, n), part.k[s].segment(at, n), h, s, part.x[s + 1].segment(at, n));
    });
    return;
  }
  for_own_blocks(l, part.own, [&](Eigen::Index at, Eigen::Index n) {
    rk4::combine(part.x[0].segment(at, n), part.k[0].segment(at, n), part.k[1].segment(at, n), part.k[2].segment(at, n),
                 part.k[3].segment(at, n), h);
  });
  part.system.after_step(t_next, part.x[0]);
}

void gather(const std::vector<Part>& parts, const StateLayout& global, Eigen::VectorXd& y) {
  y.resize(global.size());
  for (const Part& p : parts)
    for (Eigen::Index i = 0; i < p.own; ++i)
      copy_body(p.system.layout(), p.x[0], i, global, y, p.sub->own[static_cast<std::size_t>(i)]);
}

std::optional<Divergence> check(const std::vector<Part>& parts) {
  std::optional<Divergence> first;
  for (const Part& p : parts) {
    Eigen::VectorXd own(13 * p.own);
    const StateLayout local{p.own};
    for (Eigen::Index i = 0; i < p.own; ++i) copy_body(p.system.layout(), p.x[0], i, local, own, i);
    if (auto d = find_divergence(local, own)) {
      d->body = p.sub->own[static_cast<std::size_t>(d->body)];
      if (!first || d->body < first->body) first = d;
    }
  }
  return first;
}

}  // namespace mbsflow::partitioned
