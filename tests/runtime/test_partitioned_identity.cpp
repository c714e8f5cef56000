// The rule the design holds above all: a tightly coupled run gives bit for bit the same
// snapshots whatever the partition count, thread count and executor.
#include <catch2/catch.hpp>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "partitioned_state.hpp"
#include "reference_run.hpp"

using namespace mbsflow;

namespace {

Model with_short_run(Model m) {
  m.simulation.step = 0.5 * estimate_stable_step(m).step;  // well inside, so the model moves smoothly
  m.simulation.t_end = m.simulation.t_start + 40 * *m.simulation.step;
  m.simulation.output_every = 5;
  return m;
}

// A chain and a plate side by side plus a free body: three disconnected parts.
Model disconnected() {
  ChainParams c;
  c.bodies = 12;
  GridParams g;
  g.rows = 3;
  g.cols = 4;
  Model a = make_chain(c);
  const Model b = make_grid(g);
  const int offset = static_cast<int>(a.bodies.size());
  for (Body body : b.bodies) {
    body.position[2] += 5.0;
    a.bodies.push_back(body);
  }
  for (Joint j : b.joints) {
    if (j.body1 != ground) j.body1 += offset;
    j.body2 += offset;
    if (j.body1 == ground) j.point1.set(2, j.point1[2] + 5.0);
    a.joints.push_back(j);
  }
  Body free_body = b.bodies[0];
  free_body.name = "free";
  free_body.position = {0, 3, 0};
  free_body.angular_velocity = {1, 2, 3};
  a.bodies.push_back(free_body);
  a.name = "disconnected";
  return a;
}

std::vector<Model> models() {
  TrainParams train;
  train.wagons = 3;  // 21 bodies
  GridParams grid;
  grid.rows = 6;
  grid.cols = 7;
  ChainParams chain;
  chain.bodies = 40;
  RandomTreeParams tree;
  tree.bodies = 50;
  tree.cycles = 12;
  return {with_short_run(make_chain(chain)), with_short_run(make_grid(grid)), with_short_run(make_train(train)),
          with_short_run(make_random_tree(tree)), with_short_run(disconnected())};
}

}  // namespace

TEST_CASE("partitioned runs equal the single-partition run bit for bit", "[runtime][identity]") {
  for (Model m : models())
    for (Method method : {Method::rk4, Method::dopri5}) {
    const test::MemorySink reference = test::reference_run(m, method);
    REQUIRE(reference.states.size() == 9);  // DOPRI5 writes on the same grid, from its dense output
    // The model really moved, so equality means something.
    REQUIRE(reference.states.back() != reference.states.front());
    for (int k : {1, 2, 3, 7, 16})
      for (Partitioner partitioner : {Partitioner::band, Partitioner::metis}) {
      const Decomposition d = decompose(m, k, partitioner);
      for (int threads : {1, 2, 4})
        for (Executor ex : {Executor::flow_graph, Executor::barrier}) {
          test::MemorySink sink;
          run_partitioned(m, d, options_from_model(m), {threads, ex}, &sink);
          INFO(m.name << ", " << method_name(method) << ", " << k << " partitions by " << partitioner_name(partitioner) << ", " << threads << " threads, "
                      << (ex == Executor::flow_graph ? "flow graph" : "barrier"));
          REQUIRE(sink.states.size() == reference.states.size());
          CHECK(test::same_snapshots(sink, reference));
        }
    }
  }
}

TEST_CASE("decomposition: balanced band cuts, symmetric exchange plans, errors", "[runtime]") {
  ChainParams c;
  c.bodies = 1000;
  const Model m = make_chain(c);
  const Decomposition d = decompose(m, 4);
  CHECK(d.cut_joints == 3);  // a chain cut into 4 pieces
  CHECK(d.imbalance < 0.01);
  for (std::size_t p = 0; p < d.submodels.size(); ++p)
    for (const auto& e : d.submodels[p].exchanges) {
      // Whoever p takes ghosts from takes ghosts from p.
      bool back = false;
      for (const auto& f : d.submodels[static_cast<std::size_t>(e.neighbour)].exchanges) back = back || f.neighbour == static_cast<int>(p);
      CHECK(back);
      CHECK(e.from.size() == e.to.size());
    }
  CHECK_THROWS_WITH(decompose(m, 0), "partitions: must be >= 1 (got 0)");
  CHECK_THROWS_WITH(decompose(m, 1001), "partitions: 1001 is more than the model's 1000 bodies");
  std::vector<int> part(1000, 0);
  CHECK_THROWS_WITH(decompose(m, part, 2), "partition: part 1 has no bodies");
}

TEST_CASE("METIS cuts a bushy tree far better than band cuts, best keeps the faster one", "[runtime]") {
  RandomTreeParams p;
  p.bodies = 2000;
  p.cycles = 100;
  const Model m = make_random_tree(p);
  const Decomposition band = decompose(m, 4, Partitioner::band), metis = decompose(m, 4, Partitioner::metis);
  INFO("cut joints: band " << band.cut_joints << ", metis " << metis.cut_joints);
  CHECK(metis.partitioner == Partitioner::metis);
  CHECK(metis.cut_joints * 4 < band.cut_joints);
  CHECK(metis.imbalance < 0.05);
  const Decomposition best = decompose(m, 4);
  CHECK(best.estimated_time() == std::min(band.estimated_time(), metis.estimated_time()));
  ChainParams c;
  c.bodies = 500;
  CHECK(decompose(make_chain(c), 5).cut_joints == 4);  // a chain: k - 1 cuts
}

TEST_CASE("RK4 parts keep three state vectors and two derivatives, DOPRI5 parts seven each", "[runtime][identity]") {
  ChainParams c;
  c.bodies = 40;
  const Model m = make_chain(c);
  const Decomposition d = decompose(m, 2, Partitioner::band);
  const partitioned::Part rk4(m, d.submodels[0], 4, true), plain(m, d.submodels[0], 4), dopri5(m, d.submodels[0], 7, true);
  CHECK(rk4.rk4_folded);
  CHECK(rk4.x.size() == 3);
  CHECK(rk4.k.size() == 2);
  CHECK(&rk4.input(3) == &rk4.input(1));  // stage inputs 1 and 3 share a vector
  CHECK(&rk4.input(2) != &rk4.input(1));
  CHECK(&rk4.derivative(1) == &rk4.derivative(3));  // k2, k3, k4 one after another; k[0] the sum
  CHECK(&rk4.derivative(2) == &rk4.derivative(3));
  CHECK(&rk4.derivative(0) != &rk4.derivative(1));
  CHECK(!plain.rk4_folded);
  CHECK(plain.x.size() == 4);
  CHECK(!dopri5.rk4_folded);
  CHECK(dopri5.x.size() == 7);
  CHECK(dopri5.k.size() == 7);
}

TEST_CASE("a part lets its joints' records go: same Jacobian pattern and right-hand side as its local model's system",
          "[runtime][identity]") {
  ChainParams c;
  c.bodies = 40;
  const Model m = make_chain(c);
  const Decomposition d = decompose(m, 3, Partitioner::band);
  const Submodel& middle = d.submodels[1];  // ghosts on both sides
  partitioned::Part part(m, middle, 4, true);
  MultibodySystem local(submodel_model(m, middle), middle.integrated());
  REQUIRE(local.model().joints.size() == middle.joints.size());
  CHECK(part.system.model().joints.empty());
  CHECK(part.system.model().bodies.size() == local.model().bodies.size());
  const Eigen::SparseMatrix<double> a = part.system.jacobian_pattern(), b = local.jacobian_pattern();
  REQUIRE(a.nonZeros() == b.nonZeros());
  CHECK(Eigen::MatrixXd(a) == Eigen::MatrixXd(b));
  Eigen::VectorXd y = local.initial_state();
  y += 1e-3 * Eigen::VectorXd::LinSpaced(y.size(), -1.0, 1.0);  // deflected joints
  Eigen::VectorXd fa = Eigen::VectorXd::Zero(y.size()), fb = fa;  // the ghosts' rows are not written
  part.system.rhs(0.1, y, fa);
  local.rhs(0.1, y, fb);
  CHECK(fa == fb);
}
