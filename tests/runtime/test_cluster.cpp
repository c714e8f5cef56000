// Runs across processes, with the workers as threads of the test: the coordinator and
// workers talk over real ZeroMQ sockets (tcp on 127.0.0.1 and ipc), and the results equal
// the one-process run bit for bit. Process-level faults are tested in tests/apps.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <tuple>
#include <filesystem>
#include <future>
#include <thread>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "cluster_wire.hpp"
#include "pendulum_row.hpp"
#include "thread_workers.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

TEST_CASE("cluster runs over tcp and ipc equal the one-process run bit for bit", "[runtime][cluster]") {
  ChainParams chain;
  chain.bodies = 30;
  GridParams grid;
  grid.rows = 4;
  grid.cols = 5;
  for (const Model& m : {short_run(make_chain(chain), 45), short_run(make_grid(grid), 30)}) {
    MultibodySystem sys(m);
    test::MemorySink reference;
    const RunOptions o = options_from_model(m);
    run_simulation(sys, o, &reference);
    REQUIRE(reference.states.back() != reference.states.front());
    const std::string json = model_to_json(m);
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("mbsflow_cluster_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    for (const std::string transport : {"tcp", "ipc"})
      for (int workers : {2, 3}) {
        std::vector<std::string> listen;
        for (int i = 0; i < workers; ++i)
          listen.push_back(transport == "tcp" ? "tcp://127.0.0.1:*" : "ipc://" + (dir / ("ctl" + std::to_string(i))).string());
        ThreadWorkers pool(listen);
        ClusterConfig c = transport == "tcp" ? cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*")
                                             : cluster_of(pool.endpoints, "ipc://" + (dir / "data").string(),
                                                          "ipc://" + (dir / "results").string());
        if (transport == "tcp")
          for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
        c.workers[0].weight = 2;  // uneven: the first worker runs two submodels
        const Decomposition d = decompose(m, cluster_submodels(c));
        test::MemorySink sink;
        ClusterStats stats;
        const RunSummary r = run_cluster(m, json, d, c, o, &sink, &stats);
        INFO(m.name << " on " << workers << " workers over " << transport);
        CHECK(r.steps == static_cast<long>(std::round((o.t_end - o.t_start) / o.step)));
        REQUIRE(sink.states.size() == reference.states.size());
        CHECK(sink.times == reference.times);
        bool identical = true;
        for (std::size_t i = 0; i < sink.states.size(); ++i) identical = identical && sink.states[i] == reference.states[i];
        CHECK(identical);
        CHECK(r.final_state == reference.states.back());
        CHECK(stats.messages > 0);
        CHECK(stats.bytes_per_stage > 0.0);
        for (const std::string& e : pool.errors) CHECK(e.empty());
      }
    std::filesystem::remove_all(dir);
  }
}

TEST_CASE("a model longer than one set-up part reaches the workers whole: the run equals the one-process run bit for bit",
          "[runtime][cluster]") {
  ChainParams chain;
  chain.bodies = 24000;
  Model m = short_run(make_chain(chain), 3);
  m.simulation.output_every = 1;
  const std::string json = model_to_json(m);
  REQUIRE(json.size() > wire::model_part_bytes);  // two parts, the second one short
  MultibodySystem sys(m);
  test::MemorySink reference;
  const RunOptions o = options_from_model(m);
  run_simulation(sys, o, &reference);
  ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
  ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
  for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
  const Decomposition d = decompose(m, cluster_submodels(c));
  test::MemorySink sink;
  run_cluster(m, json, d, c, o, &sink, nullptr);
  REQUIRE(sink.states.size() == reference.states.size());
  CHECK(sink.states.back() == reference.states.back());
  for (const std::string& e : pool.errors) CHECK(e.empty());
}

TEST_CASE("tight DOPRI5 across processes equals the one-process run bit for bit, rejected attempts included",
          "[runtime][cluster]") {
  ChainParams chain;
  chain.bodies = 30;
  Model m = short_run(make_chain(chain), 45);
  m.simulation.method = Method::dopri5;
  RunOptions o = options_from_model(m);
  o.rtol = o.atol = 1e-8;
  o.step *= 32;  // a first step far too long: the first attempts are rejected
  o.output_interval = (o.t_end - o.t_start) / 10;  // dense output between steps
  MultibodySystem sys(m);
  test::MemorySink reference;
  run_simulation(sys, o, &reference);
  REQUIRE(reference.states.size() == 11);
  REQUIRE(reference.states.back() != reference.states.front());
  for (auto [workers, delay] : {std::pair{2, 0.0}, std::pair{3, 0.0}, std::pair{3, 0.001}}) {
    ThreadWorkers pool(std::vector<std::string>(static_cast<std::size_t>(workers), "tcp://127.0.0.1:*"));
    ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
    for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
    c.workers[0].weight = 2;  // the first worker runs two submodels
    const Decomposition d = decompose(m, cluster_submodels(c));
    test::MemorySink in_process;
    const RunSummary one = run_partitioned(m, d, o, {2, Executor::flow_graph}, &in_process);
    REQUIRE(one.rejected > 0);
    test::MemorySink sink;
    const RunSummary r = run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr, {nullptr, delay});
    INFO(workers << " workers, exchange delay " << delay << " s");
    CHECK(sink.times == reference.times);
    CHECK(sink.states == reference.states);
    CHECK(r.final_state == reference.states.back());
    CHECK(in_process.states == reference.states);
    CHECK(r.steps == one.steps);
    CHECK(r.rejected == one.rejected);
    CHECK(r.evaluations == one.evaluations);
    for (const std::string& e : pool.errors) CHECK(e.empty());
  }
}

TEST_CASE("tight runs across processes start from the state projected onto rigid joints, bit for bit", "[runtime][cluster][rigid]") {
  const Model m = pendulum_row();  // its rods' initial velocities are projected onto the joints
  for (Method method : {Method::rk4, Method::dopri5}) {
    RunOptions o = options_from_model(m);
    o.method = method;
    MultibodySystem sys(m);
    const Eigen::VectorXd y0 = sys.initial_state();
    const Vec3& given = m.bodies[1].velocity;
    REQUIRE((y0.segment<3>(sys.layout().velocity(1)) - Eigen::Vector3d(given[0], given[1], given[2])).norm() > 1e-3);
    test::MemorySink reference;
    run_simulation(sys, o, &reference);
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
    ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
    for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
    const Decomposition d = decompose(m, cluster_submodels(c));
    REQUIRE(d.cut_joints > 0);
    test::MemorySink sink;
    run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr);
    INFO(method_name(method));
    REQUIRE(sink.states.size() == reference.states.size());
    CHECK(sink.states == reference.states);
    for (const std::string& e : pool.errors) CHECK(e.empty());
  }
}

TEST_CASE("cluster: submodels by weight or by list", "[runtime][cluster]") {
  ClusterConfig c;
  c.workers.resize(3);
  c.workers[0].weight = 2;
  CHECK(cluster_submodels(c) == 4);
  CHECK(assign_submodels(c, 4) == std::vector<int>{0, 0, 1, 2});
  CHECK(assign_submodels(c, 8) == std::vector<int>{0, 0, 0, 0, 1, 1, 2, 2});
  CHECK_THROWS_AS(assign_submodels(c, 2), InputError);
  c.workers[0].submodels = {2};
  c.workers[1].submodels = {0};
  c.workers[2].submodels = {1, 3};
  CHECK(cluster_submodels(c) == 4);
  CHECK(assign_submodels(c, 4) == std::vector<int>{1, 2, 0, 2});
  CHECK_THROWS_WITH(assign_submodels(c, 5), "submodel 4 is listed by no worker");
  c.workers[1].submodels = {2};
  CHECK_THROWS_WITH(assign_submodels(c, 4), "submodel 2 is listed by two workers");
}

TEST_CASE("cluster: an unreachable worker is an error within the connect timeout", "[runtime][cluster]") {
  ChainParams chain;
  chain.bodies = 8;
  const Model m = short_run(make_chain(chain), 10);
  ClusterConfig c = cluster_of({"tcp://127.0.0.1:1"}, "", "tcp://127.0.0.1:*");
  c.timeouts.connect_s = 0.5;
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(run_cluster(m, model_to_json(m), decompose(m, 1), c, options_from_model(m), nullptr),
                    Catch::Contains("worker w0 (tcp://127.0.0.1:1, submodels 0) did not answer within 0.5 s"));
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(3));
}

TEST_CASE("loosely coupled cluster runs equal the one-process loose run bit for bit, with an exact lag and delayed messages too",
          "[runtime][cluster][loose]") {
  ChainParams chain;
  chain.bodies = 30;
  Model m = short_run(make_chain(chain), 42);
  // An overlap across the whole chain, from neighbours' neighbours too; error control
  // taking macro steps again in every worker alike.
  for (auto [method, lag, steps, tol] :
       {std::tuple{Method::rk4, 0, 3, 0.0}, std::tuple{Method::dopri5, 0, 3, 0.0}, std::tuple{Method::rk4, 2, 3, 0.0},
        std::tuple{Method::rk4, 0, 14, 0.0}, std::tuple{Method::rk4, 0, 14, 1e-12}}) {
    m.simulation.method = method;
    RunOptions o = options_from_model(m);
    o.rtol = o.atol = 1e-9;
    LooseOptions lo;
    lo.macro_step = steps * o.step;
    lo.coupling_tol = tol;
    lo.overlap = tol > 0.0 ? 0.5 * o.step : -1.0;  // short: errors the tolerance rejects
    lo.extrapolation = 2;
    lo.max_lag = lag;
    lo.exact_lag = true;
    const Decomposition d = decompose(m, 3);
    if (steps > 3 && tol == 0.0) CHECK(loose_decomposition(m, d, lo).submodels[0].borrowed.size() > d.submodels[1].own.size());
    test::MemorySink reference;
    LooseStats st;
    run_loose(m, d, o, lo, &reference, &st);
    if (tol > 0.0) CHECK(st.rejected > 0);
    REQUIRE(reference.states.size() == 7);  // the start and every 7 steps
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
    ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
    for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
    c.workers[0].weight = 2;
    test::MemorySink sink;
    run_cluster(m, model_to_json(m), d, c, o, &sink, nullptr, {&lo, method == Method::rk4 ? 0.002 : 0.0});
    INFO(method_name(method) << ", lag " << lag << ", macro step of " << steps << " steps, tolerance " << tol);
    CHECK(sink.times == reference.times);
    CHECK(sink.states == reference.states);
  }
}
