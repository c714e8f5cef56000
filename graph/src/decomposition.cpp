#include "mbsflow/graph/decomposition.hpp"

#include <algorithm>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/cuthill_mckee_ordering.hpp>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>

#include "mbsflow/error.hpp"
#include "mbsflow/words.hpp"
#include "mbsflow/graph/force_element.hpp"
#include "metis_partition.hpp"
#include "submodel_links.hpp"

namespace mbsflow {
namespace {

using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS,
                                    boost::property<boost::vertex_color_t, boost::default_color_type,
                                                    boost::property<boost::vertex_degree_t, int>>>;

bool is_body(int b) { return b != ground; }

// A model's force element in a submodel: the same element, its bodies at local indices.
class LocalForceElement final : public ForceElement {
 public:
  LocalForceElement(std::shared_ptr<const ForceElement> e, std::vector<int> model_bodies, std::vector<int> local_bodies)
      : e_(std::move(e)), model_(std::move(model_bodies)), local_(std::move(local_bodies)) {}
  std::vector<int> bodies() const override { return local_; }
  void evaluate(double t, const Kinematics& k, std::span<Wrench> out) const override {
    e_->evaluate(t, Kinematics(k, model_, local_), out);
  }
  double energy(double t, const Kinematics& k) const override { return e_->energy(t, Kinematics(k, model_, local_)); }

 private:
  std::shared_ptr<const ForceElement> e_;
  std::vector<int> model_, local_;
};

}  // namespace

std::vector<int> cuthill_mckee_order(const Model& m) {
  const std::size_t n = m.bodies.size();
  Graph g(n);
  for (const Joint& j : m.joints)
    if (is_body(j.body1)) boost::add_edge(static_cast<std::size_t>(j.body1), static_cast<std::size_t>(j.body2), g);
  std::vector<Graph::vertex_descriptor> order;
  order.reserve(n);
  // Boost's overload without a start vertex orders every connected part, each from a
  // pseudo-peripheral vertex; the reverse order is the reverse Cuthill-McKee order.
  boost::cuthill_mckee_ordering(g, std::back_inserter(order), boost::get(boost::vertex_color, g),
                                boost::make_degree_map(g));
  std::reverse(order.begin(), order.end());
  return {order.begin(), order.end()};
}

std::vector<double> body_costs(const Model& m) {
  // Measured by `mbsflow bench rhs`: ~28 ns per body, ~78 ns per joint; half of each
  // joint to each of its bodies (a cut joint is computed on both sides).
  std::vector<double> cost(m.bodies.size(), 28.0);
  for (const Joint& j : m.joints) {
    cost[static_cast<std::size_t>(j.body2)] += is_body(j.body1) ? 39.0 : 78.0;
    if (is_body(j.body1)) cost[static_cast<std::size_t>(j.body1)] += 39.0;
  }
  // A flexible body's rates (its mass matrix M(eta) and their solve) on its frame: about
  // 2.8 us + 18 ns ne^2 (mbsflow run, --threads 1, of the bar of examples/fe reduced with
  // --modes 4 .. 40 and hung on a bushing: 2.4, 4.6, 10 and 31 us per evaluation).
  for (const FlexibleBody& f : m.flexible) {
    const double ne = f.data ? f.data->modes() : 0;
    cost[static_cast<std::size_t>(f.frame)] += 2800.0 + 18.0 * ne * ne;
  }
  return cost;
}

int Submodel::local_index(int global) const {
  auto find = [&](const std::vector<int>& v) {
    const auto it = std::lower_bound(v.begin(), v.end(), global);
    return it != v.end() && *it == global ? static_cast<int>(it - v.begin()) : -1;
  };
  if (const int i = find(own); i >= 0) return i;
  if (const int i = find(borrowed); i >= 0) return static_cast<int>(own.size()) + i;
  if (const int i = find(ghosts); i >= 0) return integrated() + i;
  return -1;
}

const char* partitioner_name(Partitioner p) {
  return p == Partitioner::band ? "band" : p == Partitioner::metis ? "metis" : "best";
}

namespace {

std::vector<int> band_partition(const Model& m, const std::vector<double>& cost, int k) {
  const int n = static_cast<int>(m.bodies.size());
  const std::vector<int> order = cuthill_mckee_order(m);
  const double total = std::accumulate(cost.begin(), cost.end(), 0.0);
  // Cut the band into k pieces of equal cost: piece p ends where the running cost
  // passes (p+1)/k of the total, leaving at least one body for each later piece.
  std::vector<int> part(static_cast<std::size_t>(n));
  double running = 0.0;
  int p = 0;
  for (int i = 0; i < n; ++i) {
    const int b = order[static_cast<std::size_t>(i)];
    part[static_cast<std::size_t>(b)] = p;
    running += cost[static_cast<std::size_t>(b)];
    const int left = n - 1 - i;  // bodies after this one
    if (p < k - 1 && (running >= total * (p + 1) / k || left == k - 1 - p)) ++p;
  }
  return part;
}

}  // namespace

namespace {

// The bodies' pieces when join(a, b) is called for each pair joins(join) makes one: numbered
// in the order of their first body.
template <class Joins>
std::vector<int> pieces_joined(std::size_t n, Joins joins) {
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  joins([&](int a, int b) { parent[static_cast<std::size_t>(root(a))] = root(b); });
  std::vector<int> piece(n), of_root(n, -1);
  int count = 0;
  for (std::size_t b = 0; b < n; ++b) {
    int& p = of_root[static_cast<std::size_t>(root(static_cast<int>(b)))];
    if (p < 0) p = count++;
    piece[b] = p;
  }
  return piece;
}

template <class Join>
void join_rigid(const Model& m, Join join) {
  for (const Joint& j : m.joints)
    if (is_kinematic(j.type) && j.rigid && is_body(j.body1)) join(j.body1, j.body2);
}

}  // namespace

std::vector<int> rigid_pieces(const Model& m) {
  return pieces_joined(m.bodies.size(), [&](auto join) { join_rigid(m, join); });
}

std::vector<int> uncut_pieces(const Model& m) {
  if (m.flexible.empty()) return rigid_pieces(m);
  std::vector<char> node(m.bodies.size(), 0);
  for (const FlexibleBody& f : m.flexible)
    for (int b : f.nodes) node[static_cast<std::size_t>(b)] = 1;
  auto at_node = [&](int b) { return is_body(b) && node[static_cast<std::size_t>(b)] != 0; };
  return pieces_joined(m.bodies.size(), [&](auto join) {
    join_rigid(m, join);
    for (const FlexibleBody& f : m.flexible)
      for (int b : f.nodes) join(f.frame, b);
    for (const Joint& j : m.joints)
      if (is_body(j.body1) && (at_node(j.body1) || at_node(j.body2))) join(j.body1, j.body2);
    for (const auto& e : m.force_elements) {
      const std::vector<int> bodies = e->bodies();
      if (std::any_of(bodies.begin(), bodies.end(), at_node))
        for (int b : bodies) join(bodies.front(), b);
    }
  });
}

std::vector<int> flexible_piece_of(const Model& m) {
  std::vector<int> of(m.bodies.size(), -1);
  if (m.flexible.empty()) return of;
  const std::vector<int> piece = uncut_pieces(m);
  std::vector<int> holder(m.bodies.size(), -1);  // per piece; pieces are at most as many as bodies
  for (std::size_t f = 0; f < m.flexible.size(); ++f) holder[static_cast<std::size_t>(piece[static_cast<std::size_t>(m.flexible[f].frame)])] = static_cast<int>(f);
  for (std::size_t b = 0; b < of.size(); ++b) of[b] = holder[static_cast<std::size_t>(piece[b])];
  return of;
}

namespace {

// The model with each rigid piece contracted to one body (cost: the piece's), joints
// between pieces kept: what the partitioners cut.
Model contracted(const Model& m, const std::vector<int>& piece, int pieces) {
  Model c;
  c.bodies.resize(static_cast<std::size_t>(pieces));
  for (const Joint& j : m.joints) {
    Joint copy;
    copy.body2 = piece[static_cast<std::size_t>(j.body2)];
    copy.body1 = is_body(j.body1) ? piece[static_cast<std::size_t>(j.body1)] : ground;
    if (copy.body1 != copy.body2) c.joints.push_back(copy);
  }
  return c;
}

std::string piece_sizes(const std::vector<int>& piece, int pieces) {
  std::vector<int> size(static_cast<std::size_t>(pieces), 0);
  for (int p : piece) ++size[static_cast<std::size_t>(p)];
  std::sort(size.rbegin(), size.rend());
  std::string out;
  for (std::size_t i = 0; i < size.size() && i < 12; ++i) out += (i ? ", " : "") + std::to_string(size[i]);
  return out + (size.size() > 12 ? ", ..." : "");
}

}  // namespace

Partitioner partitioner_named(std::string_view name) {
  if (name == "best") return Partitioner::best;
  if (name == "band") return Partitioner::band;
  if (name == "metis") return Partitioner::metis;
  throw InputError("{partitioner=" + std::string(name) + "}: best, band or metis");
}

Decomposition decompose(const Model& m, int k, Partitioner partitioner) {
  const int n = static_cast<int>(m.bodies.size());
  if (k < 1) throw InputError("partitions: must be >= 1 (got " + std::to_string(k) + ")");
  if (k > n)
    throw InputError("partitions: " + std::to_string(k) + " is more than the model's " + count_of(n, "body", "bodies"));
  // Rigid pieces are never cut: the partitioners cut the model with each piece contracted
  // to one vertex (the model itself when there are no rigid joints), then each body goes
  // where its piece went.
  const std::vector<int> piece = uncut_pieces(m);
  const int pieces = piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1;
  if (k > pieces)
    throw InputError("partitions: " + count_of(k, "submodel") + ", but rigid joints" +
                     (m.flexible.empty() ? "" : " and flexible bodies (a part with what is joined to its nodes)") +
                     " leave only " + count_of(pieces, "piece") + " that may be cut apart (bodies per piece: " +
                     piece_sizes(piece, pieces) + "); use fewer submodels or make joints between clusters compliant");
  const std::vector<double> body_cost = body_costs(m);
  std::vector<double> cost(static_cast<std::size_t>(pieces), 0.0);
  for (std::size_t b = 0; b < piece.size(); ++b) cost[static_cast<std::size_t>(piece[b])] += body_cost[b];
  const bool whole = pieces == n;
  const Model c = whole ? Model{} : contracted(m, piece, pieces);
  const Model& g = whole ? m : c;
  auto decompose_pieces = [&](const std::vector<int>& of_piece) {
    std::vector<int> part(piece.size());
    for (std::size_t b = 0; b < piece.size(); ++b) part[b] = of_piece[static_cast<std::size_t>(piece[b])];
    return decompose(m, part, k);
  };
  std::optional<Decomposition> band, metis;
  if (partitioner != Partitioner::metis || k == 1) band = decompose_pieces(band_partition(g, cost, k));
  if (partitioner != Partitioner::band && k > 1)
    if (const auto part = metis_partition(g, cost, k)) {
      metis = decompose_pieces(*part);
      metis->partitioner = Partitioner::metis;
    }
  if (!metis) return band ? *band : decompose_pieces(band_partition(g, cost, k));
  if (!band || metis->estimated_time() < band->estimated_time()) return *metis;
  return *band;
}

double Decomposition::estimated_time() const {
  double t = 0.0;
  for (const Submodel& s : submodels) t = std::max(t, s.estimated_time());
  return t;
}

Decomposition decompose(const Model& m, const std::vector<int>& part, int k) {
  const std::size_t n = m.bodies.size();
  if (part.size() != n) throw InputError("partition: assigns " + std::to_string(part.size()) + " bodies, the model has " + std::to_string(n));
  Decomposition d;
  d.part_of_body = part;
  d.submodels.resize(static_cast<std::size_t>(k));
  const std::vector<double> cost = body_costs(m);
  for (std::size_t b = 0; b < n; ++b) {
    if (part[b] < 0 || part[b] >= k)
      throw InputError("partition: body " + std::to_string(b) + " is in part " + std::to_string(part[b]) + ", not in 0.." + std::to_string(k - 1));
    Submodel& s = d.submodels[static_cast<std::size_t>(part[b])];
    s.own.push_back(static_cast<int>(b));
    s.cost += cost[b];
  }
  for (std::size_t p = 0; p < d.submodels.size(); ++p)
    if (d.submodels[p].own.empty()) throw InputError("partition: part " + std::to_string(p) + " has no bodies");
  for (const Joint& j : m.joints)
    if (is_kinematic(j.type) && j.rigid && is_body(j.body1) &&
        part[static_cast<std::size_t>(j.body1)] != part[static_cast<std::size_t>(j.body2)])
      throw InputError("partition: rigid joint '" + j.name + "' joins body '" + m.bodies[static_cast<std::size_t>(j.body1)].name +
                       "' (part " + std::to_string(part[static_cast<std::size_t>(j.body1)]) + ") to body '" +
                       m.bodies[static_cast<std::size_t>(j.body2)].name + "' (part " +
                       std::to_string(part[static_cast<std::size_t>(j.body2)]) +
                       "): a cut may only pass through compliant joints, bushings and springs");
  if (!m.flexible.empty()) {
    const std::vector<int> holder = flexible_piece_of(m);
    for (std::size_t b = 0; b < n; ++b) {
      const int f = holder[b];
      if (f < 0) continue;
      const int p = part[static_cast<std::size_t>(m.flexible[static_cast<std::size_t>(f)].frame)];
      if (part[b] != p)
        throw InputError("partition: body '" + m.bodies[b].name + "' (part " + std::to_string(part[b]) +
                         ") is joined to flexible body '" + m.flexible[static_cast<std::size_t>(f)].name + "' (part " +
                         std::to_string(p) + ") at a node: a part, its nodes and the bodies joined to them are never cut apart");
    }
    for (std::size_t f = 0; f < m.flexible.size(); ++f)
      d.submodels[static_cast<std::size_t>(part[static_cast<std::size_t>(m.flexible[f].frame)])].flexible.push_back(static_cast<int>(f));
    d.flexible_tail = flexible_tail_offsets(m.flexible);
  }
  for (const Joint& j : m.joints)
    if (is_body(j.body1) && part[static_cast<std::size_t>(j.body1)] != part[static_cast<std::size_t>(j.body2)]) ++d.cut_joints;
  link_submodels(m, d);
  double max_cost = 0.0, sum = 0.0;
  for (const Submodel& s : d.submodels) {
    max_cost = std::max(max_cost, s.cost);
    sum += s.cost;
  }
  d.imbalance = max_cost / (sum / k) - 1.0;
  return d;
}

Model submodel_model(const Model& m, const Submodel& s) {
  Model local;
  local.name = m.name;
  local.gravity = m.gravity;
  local.simulation = m.simulation;
  local.bodies.reserve(s.own.size() + s.borrowed.size() + s.ghosts.size());  // exact: no growth slack
  local.joints.reserve(s.joints.size());
  for (int b : s.own) local.bodies.push_back(m.bodies[static_cast<std::size_t>(b)]);
  for (int b : s.borrowed) local.bodies.push_back(m.bodies[static_cast<std::size_t>(b)]);
  for (int b : s.ghosts) local.bodies.push_back(m.bodies[static_cast<std::size_t>(b)]);
  for (int j : s.joints) {
    Joint jt = m.joints[static_cast<std::size_t>(j)];
    jt.body1 = is_body(jt.body1) ? s.local_index(jt.body1) : ground;
    jt.body2 = s.local_index(jt.body2);
    local.joints.push_back(jt);
  }
  for (const Load& l : m.loads) {
    const int i = s.local_index(l.body);
    if (i >= 0 && i < s.integrated()) {
      Load copy = l;
      copy.body = i;
      local.loads.push_back(copy);
    }
  }
  for (const Driver& dr : m.drivers) {
    const int i = s.local_index(dr.body);
    if (i >= 0) {
      Driver copy = dr;
      copy.body = i;
      local.drivers.push_back(copy);
    }
  }
  // Flexible bodies held here, in model order: their state tail is the model's, less the others'.
  for (int f : s.flexible) {
    FlexibleBody copy = m.flexible[static_cast<std::size_t>(f)];
    copy.frame = s.local_index(copy.frame);
    for (int& b : copy.nodes) b = s.local_index(b);
    local.flexible.push_back(std::move(copy));
  }
  // Force elements on own and borrowed bodies, in model order, reading their bodies at local indices.
  const int n_own = s.integrated();
  for (const auto& e : m.force_elements) {
    std::vector<int> bodies = e->bodies(), at;
    for (int b : bodies) at.push_back(s.local_index(b));
    if (std::none_of(at.begin(), at.end(), [n_own](int i) { return i >= 0 && i < n_own; })) continue;
    if (std::find(at.begin(), at.end(), -1) != at.end())  // a decomposition made without the element
      throw InputError("a force element's bodies are not all in the submodel of its body " + std::to_string(bodies[0]) +
                       ": the decomposition was not made for this model");
    local.force_elements.push_back(std::make_shared<LocalForceElement>(e, std::move(bodies), std::move(at)));
  }
  return local;
}

std::string decomposition_dot(const Model& m, const Decomposition& d) {
  static const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                  "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  std::ostringstream o;
  o << "graph \"" << m.name << "\" {\n  node [shape=circle, style=filled, fontsize=8];\n";
  for (std::size_t p = 0; p < d.submodels.size(); ++p) {
    o << "  subgraph cluster_" << p << " {\n    label=\"submodel " << p << "\";\n";
    for (int b : d.submodels[p].own)
      o << "    b" << b << " [label=\"" << m.bodies[static_cast<std::size_t>(b)].name << "\", fillcolor=\"" << colours[p % 10]
        << "\"];\n";
    o << "  }\n";
  }
  bool has_ground = false;
  for (const Joint& j : m.joints) {
    const bool cut = is_body(j.body1) && d.part_of_body[static_cast<std::size_t>(j.body1)] != d.part_of_body[static_cast<std::size_t>(j.body2)];
    has_ground = has_ground || !is_body(j.body1);
    o << "  " << (is_body(j.body1) ? "b" + std::to_string(j.body1) : std::string("ground")) << " -- b" << j.body2
      << (cut ? " [color=red, penwidth=2]" : "") << ";\n";
  }
  if (has_ground) o << "  ground [shape=box, fillcolor=\"#dddddd\"];\n";
  o << "}\n";
  return o.str();
}

}  // namespace mbsflow
