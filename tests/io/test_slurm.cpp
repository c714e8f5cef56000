#include <catch2/catch.hpp>
#include <map>

#include "mbsflow/error.hpp"
#include "mbsflow/io/slurm.hpp"

using namespace mbsflow;
using Strings = std::vector<std::string>;

namespace {

EnvLookup env(const std::map<std::string, std::string>& vars) {
  return [vars](const char* name) -> const char* {
    const auto it = vars.find(name);
    return it == vars.end() ? nullptr : it->second.c_str();
  };
}

}  // namespace

TEST_CASE("Slurm host lists expand as scontrol show hostnames does", "[io][slurm]") {
  CHECK(expand_hostlist("node1") == Strings{"node1"});
  CHECK(expand_hostlist("n[01-03,7],gpu5") == Strings{"n01", "n02", "n03", "n7", "gpu5"});
  CHECK(expand_hostlist("n[8-11]") == Strings{"n8", "n9", "n10", "n11"});
  CHECK(expand_hostlist("n[098-101]") == Strings{"n098", "n099", "n100", "n101"});
  CHECK(expand_hostlist("r[1-2]c[3,5]") == Strings{"r1c3", "r1c5", "r2c3", "r2c5"});
  CHECK(expand_hostlist("a-[1-2].example,b") == Strings{"a-1.example", "a-2.example", "b"});
  CHECK(expand_hostlist("10.0.0.[1-2]") == Strings{"10.0.0.1", "10.0.0.2"});
  for (const char* bad : {"n[1-3", "n1-3]", "n[3-1]", "n[a-b]", "n[]", "", "n[1--2]"}) {
    INFO(bad);
    CHECK_THROWS_AS(expand_hostlist(bad), InputError);
  }
  CHECK_THROWS_AS(expand_hostlist("n[1-100000]", 1000), InputError);
  CHECK_THROWS_AS(expand_hostlist("a[1-100]b[1-100]", 1000), InputError);
}

TEST_CASE("Slurm tasks per node expand their repeat counts", "[io][slurm]") {
  CHECK(expand_tasks_per_node("4") == std::vector<int>{4});
  CHECK(expand_tasks_per_node("2(x3),1") == std::vector<int>{2, 2, 2, 1});
  CHECK(expand_tasks_per_node("1,3(x2)") == std::vector<int>{1, 3, 3});
  for (const char* bad : {"", "0", "2(x)", "2(x0)", "2x3", "2(3)", "a", "2,", "2(x3"}) {
    INFO(bad);
    CHECK_THROWS_AS(expand_tasks_per_node(bad), InputError);
  }
}

TEST_CASE("Slurm step: every task's node and local index by block and cyclic distribution", "[io][slurm]") {
  std::map<std::string, std::string> vars{{"SLURM_PROCID", "3"}, {"SLURM_NTASKS", "5"}, {"SLURM_JOB_ID", "12345"},
                                          {"SLURM_STEP_NODELIST", "n[1-3]"}, {"SLURM_STEP_TASKS_PER_NODE", "2(x2),1"}};
  SlurmStep s = slurm_step_from_env(env(vars));
  CHECK(s.rank == 3);
  CHECK(s.job_id == 12345);
  CHECK(s.task_hosts == Strings{"n1", "n1", "n2", "n2", "n3"});
  CHECK(s.task_local == std::vector<int>{0, 1, 0, 1, 0});
  CHECK(slurm_base_port(s) == 20000 + 40 * 345);
  vars["SLURM_DISTRIBUTION"] = "cyclic:block";
  s = slurm_step_from_env(env(vars));
  CHECK(s.task_hosts == Strings{"n1", "n2", "n3", "n1", "n2"});
  CHECK(s.task_local == std::vector<int>{0, 0, 0, 1, 1});
  // Without tasks per node (an allocation's variables only): spread as evenly as Slurm does.
  vars.erase("SLURM_STEP_TASKS_PER_NODE");
  vars.erase("SLURM_DISTRIBUTION");
  vars["SLURM_JOB_NODELIST"] = vars["SLURM_STEP_NODELIST"];
  vars.erase("SLURM_STEP_NODELIST");
  s = slurm_step_from_env(env(vars));
  CHECK(s.task_hosts == Strings{"n1", "n1", "n2", "n2", "n3"});
}

TEST_CASE("Slurm step: missing or contradictory variables are named", "[io][slurm]") {
  const std::map<std::string, std::string> good{{"SLURM_PROCID", "0"}, {"SLURM_NTASKS", "2"},
                                                {"SLURM_STEP_NODELIST", "a,b"}, {"SLURM_STEP_TASKS_PER_NODE", "1(x2)"}};
  const auto fails_naming = [&](const std::string& var, const char* value, const std::string& named) {
    auto vars = good;
    if (value)
      vars[var] = value;
    else
      vars.erase(var);
    INFO(var << "=" << (value ? value : "(unset)"));
    CHECK_THROWS_WITH(slurm_step_from_env(env(vars)), Catch::Contains(named));
  };
  CHECK(slurm_step_from_env(env(good)).tasks() == 2);
  fails_naming("SLURM_NTASKS", nullptr, "SLURM_NTASKS is not set");
  fails_naming("SLURM_PROCID", "2", "not below SLURM_NTASKS");
  fails_naming("SLURM_PROCID", "x", "SLURM_PROCID='x'");
  fails_naming("SLURM_STEP_NODELIST", nullptr, "SLURM_JOB_NODELIST");
  fails_naming("SLURM_STEP_TASKS_PER_NODE", "1(x3)", "2 nodes in the node list but tasks given for 3");
  fails_naming("SLURM_STEP_TASKS_PER_NODE", "2,1", "add up to 3");
  fails_naming("SLURM_DISTRIBUTION", "arbitrary", "--distribution=block or cyclic");
}

TEST_CASE("Slurm cluster: task 0 coordinates and workers sit on their nodes' ports with one key pair", "[io][slurm]") {
  SlurmStep s;
  s.task_hosts = {"n1", "n1", "10.0.0.2"};
  s.task_local = {0, 1, 0};
  const CurveKeyPair keys{"pub", "sec"};
  const ClusterConfig c = slurm_cluster(s, 7000, keys);
  CHECK(c.results_bind == "tcp://*:7000");
  CHECK(c.results_address == "tcp://n1:7000");
  REQUIRE(c.workers.size() == 2);
  CHECK(c.workers[0].address == "tcp://n1:7002");
  CHECK(c.workers[0].data_bind == "tcp://*:7003");
  CHECK(c.workers[1].address == "tcp://10.0.0.2:7000");
  CHECK(c.workers[1].data_bind == "tcp://10.0.0.2:7001");  // a numeric address binds itself
  CHECK(slurm_worker_listen(s, 7000, 1) == "tcp://*:7002");
  CHECK(slurm_worker_listen(s, 7000, 2) == "tcp://10.0.0.2:7000");
  CHECK(c.coordinator_key == "pub");
  CHECK(c.workers[1].public_key == "pub");
  CHECK_THROWS_AS(slurm_cluster(s, 65533, keys), InputError);
}
