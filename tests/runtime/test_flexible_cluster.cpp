// A model with a flexible body on worker processes (threads of this process, real ZeroMQ
// sockets on loopback): the workers read the part file the model names, each sends its
// share of the state with the modes of the parts it holds, and tight runs (RK4, DOPRI5),
// loose runs and a run resumed from a checkpoint taken on workers equal the one-process
// runs bit for bit.
#include <catch2/catch.hpp>
#include <filesystem>
#include <unistd.h>

#include "analysis/spring_lattice.hpp"
#include "flexible_rig.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/reduced_part_file.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/run.hpp"
#include "memory_sink.hpp"
#include "thread_workers.hpp"

using namespace mbsflow;
using namespace mbsflow::test;

namespace {

// The rig of flexible_rig.hpp with its bar read from a part file written here (the workers
// read it again by the path the model's text names).
Model rig_from_file(const std::filesystem::path& dir) {
  const SpringLattice lattice = bar_lattice();
  FeMesh mesh;
  for (std::size_t i = 0; i < lattice.dof_position.size(); i += 3) {
    const long id = static_cast<long>(mesh.node_id.size()) + 1;
    mesh.node_index[id] = mesh.node_id.size();
    mesh.node_id.push_back(id);
    mesh.node_position.push_back(lattice.dof_position[i]);
  }
  const std::string file = (dir / "bar.h5").string();
  write_reduced_part(file, bar_part(4, {1, 2, 3, 24}), lattice.fe.dofs, mesh, {"a lattice of springs", "test"});
  const Model part = read_model_text(R"({"name": "flexible_rig", "bodies": [{"name": "bar", "type": "flexible", "file": ")" +
                                         file + R"(", "position": [0, 0, 0]}]})",
                                     "rig");
  return hanging_rig(part).m;
}

RunPlan on_workers(const Model& m, ThreadWorkers& pool, std::optional<LooseOptions> loose = {}) {
  ClusterConfig c = cluster_of(pool.endpoints, "", "tcp://127.0.0.1:*");
  for (auto& w : c.workers) w.data_bind = "tcp://127.0.0.1:*";
  c.workers[0].weight = 2;  // three submodels: the part's and two others
  RunPlan plan;
  plan.options = options_from_model(m);
  plan.partition = decompose(m, cluster_submodels(c));
  plan.cluster = c;
  plan.model_json = model_to_json(m);
  plan.loose = loose;
  return plan;
}

struct TempDir {
  std::filesystem::path path = std::filesystem::temp_directory_path() / ("mbsflow_flexible_cluster_" + std::to_string(::getpid()));
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() { std::filesystem::remove_all(path); }
};

}  // namespace

TEST_CASE("a model with a flexible body runs on worker processes bit for bit as in one process, tight and loose",
          "[runtime][cluster][flexible]") {
  const TempDir dir;
  Model m = rig_from_file(dir.path);
  REQUIRE(m.flexible.size() == 1);
  for (Method method : {Method::rk4, Method::dopri5}) {
    INFO(method_name(method));
    m.simulation.method = method;
    m.simulation.rtol = m.simulation.atol = 1e-7;
    RunPlan whole;
    whole.options = options_from_model(m);
    test::MemorySink reference;
    const RunSummary ref = run(m, whole, &reference);
    REQUIRE(reference.states.size() > 2);
    const Eigen::Index tail = MultibodySystem(m).flexible_state(0);
    REQUIRE(ref.final_state.segment(tail, 8).norm() > 1e-6);  // the bar deforms
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
    test::MemorySink sink;
    const RunSummary r = run(m, on_workers(m, pool), &sink);
    CHECK(same_snapshots(sink, reference));
    CHECK(r.final_state == ref.final_state);
    for (const std::string& e : pool.errors) CHECK(e.empty());
  }
  m.simulation.method = Method::rk4;
  LooseOptions lo;
  lo.macro_step = 4 * *m.simulation.step;
  lo.extrapolation = 2;
  RunPlan here;
  here.options = options_from_model(m);
  here.partition = decompose(m, 3);
  here.loose = lo;
  test::MemorySink reference;
  run(m, here, &reference);
  ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
  test::MemorySink sink;
  run(m, on_workers(m, pool, lo), &sink);
  CHECK(same_snapshots(sink, reference));
}

TEST_CASE("a run with a flexible body on workers resumes from its checkpoints bit for bit, on workers or threads",
          "[runtime][cluster][flexible][checkpoint]") {
  const TempDir dir;
  Model m = rig_from_file(dir.path);
  RunPlan whole;
  whole.options = options_from_model(m);
  test::MemorySink reference;
  const RunSummary ref = run(m, whole, &reference);
  std::vector<std::vector<std::uint8_t>> states;
  Checkpointing write;
  write.every_s = 1e-12;
  write.write = [&](std::vector<std::uint8_t>&& s) { states.push_back(std::move(s)); };
  test::MemorySink full;
  {
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
    RunPlan plan = on_workers(m, pool);
    plan.options.checkpoint = &write;
    run(m, plan, &full);
  }
  CHECK(same_snapshots(full, reference));
  REQUIRE(states.size() >= 2);
  Checkpointing resume;
  resume.resume = states[states.size() / 2];
  resume.resume_from = "checkpoint";
  {
    ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"});
    RunPlan plan = on_workers(m, pool);
    plan.options.checkpoint = &resume;
    test::MemorySink again = full;
    const RunSummary r = run(m, plan, &again);
    CHECK(same_snapshots(again, reference));
    CHECK(r.final_state == ref.final_state);
  }
  RunPlan threads;
  threads.options = options_from_model(m);
  threads.options.checkpoint = &resume;
  test::MemorySink here = full;
  const RunSummary h = run(m, threads, &here);
  CHECK(same_snapshots(here, reference));
  CHECK(h.final_state == ref.final_state);
}

TEST_CASE("a worker that cannot read a flexible body's part file ends the run with the path named",
          "[runtime][cluster][flexible]") {
  const TempDir dir;
  const Model m = rig_from_file(dir.path);
  const std::string file = (dir.path / "bar.h5").string(), elsewhere = (dir.path / "not_on_this_host.h5").string();
  // The second worker's host has no file at the model's path.
  ThreadWorkers pool({"tcp://127.0.0.1:*", "tcp://127.0.0.1:*"}, [&](std::size_t i, WorkerOptions& o) {
    if (i == 1)
      o.read_model = [&](std::string text) {
        text.replace(text.find(file), file.size(), elsewhere);
        return read_model_text(text, "model from the coordinator");
      };
  });
  CHECK_THROWS_WITH(run(m, on_workers(m, pool), nullptr), Catch::Contains("not_on_this_host.h5: no such file"));
}
