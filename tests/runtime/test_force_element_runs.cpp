// A model's force elements act in every in-process run mode: partitioned runs stay bit
// for bit the one-process run (an element joins its bodies like a joint, across cuts too),
// loosely coupled runs converge to it, and runs across processes refuse them up front.
#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/force_element.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

using namespace mbsflow;

namespace {

// A damped spring between two points of two bodies that no joint joins.
struct Tether final : ForceElement {
  int a, b;
  double k = 4e3, c = 20.0;
  Eigen::Vector3d pa{0.1, 0, 0}, pb{-0.1, 0.05, 0};
  Tether(int a_, int b_) : a(a_), b(b_) {}
  std::vector<int> bodies() const override { return {a, b}; }
  void evaluate(double, const Kinematics& k_, std::span<Wrench> out) const override {
    const Eigen::Vector3d d = k_.point(b, pb) - k_.point(a, pa);
    const Eigen::Vector3d v = k_.point_velocity(b, pb) - k_.point_velocity(a, pa);
    const Eigen::Vector3d f = k * d + c * v;  // on a, towards b
    out[0].force = f;
    out[0].torque = (k_.rotation(a) * pa).cross(f);
    out[1].force = -f;
    out[1].torque = (k_.rotation(b) * pb).cross(-f);
  }
  double energy(double, const Kinematics& k_) const override {
    return 0.5 * k * (k_.point(b, pb) - k_.point(a, pa)).squaredNorm();
  }
};

// Quadratic air drag on one body.
struct Drag final : ForceElement {
  int body;
  explicit Drag(int b) : body(b) {}
  std::vector<int> bodies() const override { return {body}; }
  void evaluate(double, const Kinematics& k, std::span<Wrench> out) const override {
    const Eigen::Vector3d v = k.velocity(body);
    out[0].force = -3.0 * v.norm() * v;
  }
};

// Reads a body it does not declare: fine in one system, refused in a submodel.
struct Nosy final : ForceElement {
  std::vector<int> bodies() const override { return {0}; }
  void evaluate(double, const Kinematics& k, std::span<Wrench> out) const override {
    out[0].force = -k.position(11) * 0.0;
  }
};

Model tethered_chain(int steps) {
  ChainParams c;
  c.bodies = 24;
  Model m = make_chain(c);
  m.force_elements = {std::make_shared<Tether>(2, 20), std::make_shared<Drag>(7), std::make_shared<Tether>(11, 12)};
  m.simulation.step = 0.5 * estimate_stable_step(m).step;
  m.simulation.t_end = steps * *m.simulation.step;
  m.simulation.output_every = 10;
  return m;
}

}  // namespace

TEST_CASE("force elements: partitioned runs equal the one-process run bit for bit", "[runtime][elements][identity]") {
  Model m = tethered_chain(60);
  for (Method method : {Method::rk4, Method::dopri5}) {
    m.simulation.method = method;
    MultibodySystem sys(m);
    test::MemorySink reference;
    run_simulation(sys, options_from_model(m), &reference);
    Model bare = m;
    bare.force_elements.clear();
    MultibodySystem bare_sys(bare);
    test::MemorySink without;
    run_simulation(bare_sys, options_from_model(bare), &without);
    REQUIRE(without.states.back() != reference.states.back());  // the elements do act
    for (int k : {2, 3, 5})
      for (Partitioner p : {Partitioner::band, Partitioner::metis}) {
        const Decomposition d = decompose(m, k, p);
        // bodies 2 and 20 are far apart along the chain: some cut puts them in different submodels
        for (int threads : {1, 2}) {
          test::MemorySink sink;
          run_partitioned(m, d, options_from_model(m), {threads, Executor::flow_graph}, &sink);
          INFO(method.name() << ", " << k << " partitions by " << partitioner_name(p) << ", " << threads << " threads");
          REQUIRE(sink.states.size() == reference.states.size());
          bool identical = sink.times == reference.times;
          for (std::size_t i = 0; i < sink.states.size(); ++i) identical = identical && sink.states[i] == reference.states[i];
          CHECK(identical);
        }
      }
  }
  const Decomposition band3 = decompose(m, 3, Partitioner::band);
  CHECK(band3.part_of_body[2] != band3.part_of_body[20]);
}

TEST_CASE("force elements: the energy of an undamped tether is part of the balance", "[runtime][elements]") {
  ChainParams c;
  c.bodies = 6;
  c.damping_ratio = 0.0;
  Model m = make_chain(c);
  auto tether = std::make_shared<Tether>(0, 5);
  tether->k = 400.0;
  tether->c = 0.0;
  m.force_elements = {tether};
  m.bodies[3].velocity = {0.0, 0.5, 0.2};
  MultibodySystem sys(m);
  const Eigen::VectorXd y0 = sys.initial_state();
  const Energy e0 = sys.energy(0.0, y0);
  REQUIRE(e0.elastic > 100.0 * e0.kinetic);  // the tether holds most of the energy
  std::vector<double> drift;
  for (double fraction : {0.1, 0.05}) {
    RunOptions o = options_from_model(m);
    o.t_end = 0.5;
    o.step = fraction * estimate_stable_step(m).step;
    drift.push_back(std::abs(sys.energy(o.t_end, run_simulation(sys, o, nullptr).final_state).total() - e0.total()));
  }
  INFO("energy drift " << drift[0] << ", " << drift[1] << " J of " << e0.total());
  CHECK(drift[1] < drift[0] / 16.0);  // RK4's energy error falls at its order (about 32x here)
  CHECK(drift[1] < 1e-6 * e0.total());
}

TEST_CASE("force elements: a loosely coupled run converges to the tight run", "[runtime][elements][loose]") {
  Model m = tethered_chain(200);
  m.simulation.step = 0.05 * estimate_stable_step(m).step;
  m.simulation.t_end = 200 * *m.simulation.step;
  MultibodySystem sys(m);
  const RunOptions o = options_from_model(m);
  const Eigen::VectorXd tight = run_simulation(sys, o, nullptr).final_state;
  const Decomposition d = decompose(m, 3, Partitioner::band);
  REQUIRE(d.part_of_body[2] != d.part_of_body[20]);
  double previous = 0.0;
  for (int substeps : {8, 4, 2}) {
    LooseOptions lo;
    lo.macro_step = substeps * o.step;
    lo.threads = 2;
    const Eigen::VectorXd loose = run_loose(m, d, o, lo, nullptr).final_state;
    const double gap = (loose - tight).lpNorm<Eigen::Infinity>();
    INFO(substeps << " substeps: gap " << gap);
    CHECK(gap > 0.0);
    if (previous > 0.0) CHECK(gap < 0.6 * previous);  // first-order extrapolation: at least linear
    previous = gap;
  }
}

TEST_CASE("force elements: refused across processes, and a submodel holds only what an element declares",
          "[runtime][elements]") {
  Model m = tethered_chain(10);
  ClusterConfig c;
  ClusterWorker w;
  w.name = "w0";
  w.address = "tcp://127.0.0.1:1";
  c.workers.push_back(w);
  CHECK_THROWS_AS(run_cluster(m, model_to_json(m), decompose(m, 1), c, options_from_model(m), nullptr), InputError);
  CHECK_THROWS_WITH(run_cluster(m, model_to_json(m), decompose(m, 1), c, options_from_model(m), nullptr),
                    Catch::Contains("3 force elements of this program, which worker processes do not have"));
  m.force_elements = {std::make_shared<Nosy>()};
  MultibodySystem whole(m);
  CHECK_NOTHROW(run_simulation(whole, options_from_model(m), nullptr));
  CHECK_THROWS_WITH(run_partitioned(m, decompose(m, 3, Partitioner::band), options_from_model(m), {1, Executor::flow_graph}, nullptr),
                    Catch::Contains("read body 11, which is not one of its bodies()"));
}
