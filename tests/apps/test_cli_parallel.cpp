// End-to-end tests of partitioned runs from the command line.
#include <catch2/catch.hpp>

#include "cli_support.hpp"
#include "mbsflow/io/results_file.hpp"

using namespace mbsflow::test;

TEST_CASE("partition reports submodels, writes dot and a partition file that run accepts", "[apps]") {
  const fs::path d = scratch("partition");
  const std::string dir = d.string();
  REQUIRE(run("generate random --bodies 300 --cycles 20 -o tree.json", dir).code == 0);
  REQUIRE(run("generate chain --bodies 50 -o chain.json", dir).code == 0);
  const Result p = run("partition tree.json -k 3 --dot tree.dot -o tree.part.json", dir, true);
  CHECK(p.code == 0);
  CHECK(p.out.find("submodel   bodies   joints   ghosts cut joints") != std::string::npos);
  CHECK(p.out.find("load imbalance") != std::string::npos);
  CHECK(read_text(d / "tree.dot").rfind("graph \"random-300-20\" {", 0) == 0);
  CHECK(run("run tree.json --t-end 0.01 --threads 2 --partition-file tree.part.json -q", dir).code == 0);
  const Result wrong = run("run chain.json --t-end 0.01 --partition-file tree.part.json", dir);
  CHECK(wrong.code == 2);
  CHECK(wrong.err.find("the partition is for model 'random-300-20' with 300 bodies, not for 'chain-50' with 50") !=
        std::string::npos);
  const Result too_many = run("run chain.json --partitions 51", dir);
  CHECK(too_many.code == 2);
  CHECK(trim(too_many.err).find("partitions: 51 is more than the model's 50 bodies") != std::string::npos);
  CHECK(run("partition chain.json -k 0", dir).code == 2);
  CHECK(run("run chain.json --t-end 0.01 --partitions 2 --method dopri5 -q", dir).code == 0);
  fs::remove_all(d.parent_path());
}

TEST_CASE("a partitioned run writes the same results file as a single-partition run", "[apps]") {
  const fs::path d = scratch("partitioned-results");
  const std::string dir = d.string();
  REQUIRE(run("generate grid --rows 8 --cols 9 -o grid.json", dir).code == 0);
  REQUIRE(run("run grid.json --t-end 0.05 --every 10 --threads 1 --partitions 1 -o one.h5 -q", dir).code == 0);
  REQUIRE(run("run grid.json --t-end 0.05 --every 10 --threads 2 --partitions 5 -o five.h5 -q", dir).code == 0);
  REQUIRE(run("run grid.json --t-end 0.05 --every 10 --threads 2 --partitions 3 --executor barrier -o three.h5 -q", dir).code == 0);
  const mbsflow::ResultsFile one((d / "one.h5").string()), five((d / "five.h5").string()), three((d / "three.h5").string());
  CHECK(one.time().size() > 2);
  for (const char* set : {"/time", "/bodies/position", "/bodies/orientation", "/bodies/velocity", "/bodies/angular_velocity", "/energy"}) {
    INFO(set);
    CHECK(five.read(set) == one.read(set));
    CHECK(three.read(set) == one.read(set));
  }
  CHECK(five.body_names() == one.body_names());
  fs::remove_all(d.parent_path());
}
