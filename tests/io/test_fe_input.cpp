// Finite-element input for mbsflow reduce (io/fe_input.hpp): a deck's nodes, elements
// (continued over lines), node sets (lists, sets of sets, GENERATE) and includes; the
// matrices as CalculiX stores them (one triangle: the other filled in, so that the mass
// is the model's) and as Matrix Market files; the outer faces drawn; errors with file:line.
#include <catch2/catch.hpp>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "mbsflow/error.hpp"
#include "mbsflow/io/fe_input.hpp"
#include "process_folder.hpp"

using namespace mbsflow;
namespace fs = std::filesystem;

namespace {

fs::path folder() { return test::process_folder("mbsflow_fe_input_"); }

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = folder() / name;
  std::ofstream(p) << text;
  return p;
}

// Two C3D8 elements side by side (a 2 x 1 x 1 block of unit cubes), nodes 1-12.
const char* block_deck = R"(** two cubes
*NODE, NSET=ALLNODES
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
9, 2, 0, 0
10, 2, 1, 0
11, 2, 1, 1
12, 2, 0, 1
*element, type=c3d8, elset=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 2, 9, 10, 3,
6, 12, 11, 7
*NSET, NSET=LEFT
1, 4, 5, 8
*NSET, NSET=RIGHT, GENERATE
9, 12
*NSET, NSET=ENDS
LEFT, right
*MATERIAL, NAME=STEEL
*ELASTIC
2.1e11, 0.3
)";

}  // namespace

TEST_CASE("a deck's nodes, elements over two lines, node sets and includes are read", "[io][reduce]") {
  write("block.inp", block_deck);
  const fs::path main = write("main.inp", "*INCLUDE, INPUT=block.inp\n*NSET, NSET=ONE\n1\n");
  const FeMesh m = read_fe_deck(main.string());
  REQUIRE(m.node_id.size() == 12);
  CHECK(m.node_position[m.node_index.at(11)] == Eigen::Vector3d(2, 1, 1));
  REQUIRE(m.elements.size() == 2);
  CHECK(m.elements[1].type == "C3D8");
  CHECK(m.elements[1].nodes == std::vector<long>{2, 9, 10, 3, 6, 12, 11, 7});
  CHECK(m.node_sets.at("RIGHT") == std::vector<long>{9, 10, 11, 12});
  CHECK(m.node_sets.at("ENDS") == std::vector<long>{1, 4, 5, 8, 9, 10, 11, 12});
  CHECK(m.node_sets.at("ALLNODES").size() == 12);
  CHECK(parse_node_list("ends 2-3,1", m) == std::vector<long>{1, 4, 5, 8, 9, 10, 11, 12, 2, 3});
  CHECK_THROWS_WITH(parse_node_list("13", m), Catch::Contains("node 13 is not in the deck"));
  CHECK_THROWS_WITH(parse_node_list("TOP", m), Catch::Contains("no node set TOP"));
  // The outer faces: 10 squares of the 11 (the shared one is inside), two triangles each.
  const auto faces = outer_triangles(m);
  CHECK(faces.size() == 20);
  for (const auto& f : faces) {
    const bool inner = std::count_if(f.begin(), f.end(), [](long n) { return n == 2 || n == 3 || n == 6 || n == 7; }) == 3;
    CHECK_FALSE(inner);
  }
}

TEST_CASE("a deck's errors name the file and line", "[io][reduce]") {
  const fs::path bad = write("bad.inp", "*NODE\n1, 0, 0, 0\n2, 1, x, 0\n");
  CHECK_THROWS_WITH(read_fe_deck(bad.string()), Catch::Contains("bad.inp:3: 'x' is not a number"));
  const fs::path twice = write("twice.inp", "*NODE\n1, 0, 0, 0\n1, 1, 0, 0\n");
  CHECK_THROWS_WITH(read_fe_deck(twice.string()), Catch::Contains("twice.inp:3: node 1 is defined twice"));
  const fs::path missing = write("missing.inp", "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=T3D2\n1, 1, 7\n");
  CHECK_THROWS_WITH(read_fe_deck(missing.string()), Catch::Contains("names node 7"));
  const fs::path short_element = write("short.inp", "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D8\n1, 1, 1, 1\n*STEP\n");
  CHECK_THROWS_WITH(read_fe_deck(short_element.string()), Catch::Contains("short.inp:5: element 1 has too few nodes"));
  CHECK_THROWS_AS(read_fe_deck((folder() / "none.inp").string()), InputError);
}

TEST_CASE("CalculiX's matrices: one stored triangle is filled in, so the mass is the model's", "[io][reduce]") {
  // Two nodes of 3 kg and 5 kg joined along x by a 100 N/m spring, with a consistent-like
  // coupling m12 = 1 kg: the upper triangle only, as ccx writes .sti and .mas.
  write("job.dof", "1.1\n2.1\n");
  write("job.sti", "1 1  1.0000000000000e+02\n1 2 -1.0000000000000e+02\n2 2  1.0000000000000e+02\n");
  write("job.mas", "1 1  3.0000000000000e+00\n1 2  1.0000000000000e+00\n2 2  5.0000000000000e+00\n");
  const FeMatrices m = read_calculix_matrices((folder() / "job").string());
  REQUIRE(m.dofs == std::vector<FeDof>{{1, 1}, {2, 1}});
  const Eigen::MatrixXd k = m.stiffness, mass = m.mass;
  CHECK(k(1, 0) == -100.0);
  CHECK(k(0, 1) == -100.0);
  // A rigid translation's mass: 3 + 5 + 2 * 1 with both triangles, 9 with one.
  CHECK(Eigen::Vector2d(1, 1).dot(mass * Eigen::Vector2d(1, 1)) == 10.0);
  // A file that holds both triangles is taken as it is.
  write("full.dof", "1.1\n2.1\n");
  write("full.sti", "1 1 1\n1 2 2\n2 1 2\n2 2 1\n");
  write("full.mas", "1 1 1\n2 2 1\n");
  CHECK(Eigen::MatrixXd(read_calculix_matrices((folder() / "full").string()).stiffness)(0, 1) == 2.0);
  CHECK_THROWS_WITH(read_calculix_matrices((folder() / "nojob").string()), Catch::Contains("MATRIXSTORAGE"));
  write("badrow.dof", "1.1\n");
  write("badrow.sti", "1 2 5\n");
  write("badrow.mas", "1 1 1\n");
  CHECK_THROWS_WITH(read_calculix_matrices((folder() / "badrow").string()), Catch::Contains("badrow.sti:1"));
  write("baddof.dof", "1.1\n1.9\n");
  write("baddof.sti", "1 1 1\n");
  write("baddof.mas", "1 1 1\n");
  CHECK_THROWS_WITH(read_calculix_matrices((folder() / "baddof").string()), Catch::Contains("baddof.dof:2"));
}

TEST_CASE("Matrix Market matrices, symmetric (one triangle) and general, with a DOF map", "[io][reduce]") {
  write("k.mtx", "%%MatrixMarket matrix coordinate real symmetric\n% a comment\n2 2 3\n1 1 100\n2 1 -100\n2 2 100\n");
  write("m.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 3\n2 2 5\n");
  write("map.dof", "7.2\n8.2\n");
  const FeMatrices m = read_matrix_market((folder() / "k.mtx").string(), (folder() / "m.mtx").string(), (folder() / "map.dof").string());
  CHECK(Eigen::MatrixXd(m.stiffness)(0, 1) == -100.0);
  CHECK(Eigen::MatrixXd(m.mass)(0, 1) == 0.0);
  CHECK(m.dofs[1] == FeDof{8, 2});
  write("wrong.mtx", "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 1\n");
  CHECK_THROWS_WITH(read_matrix_market((folder() / "wrong.mtx").string(), (folder() / "m.mtx").string(), (folder() / "map.dof").string()),
                    Catch::Contains("must be 2 x 2"));
}
