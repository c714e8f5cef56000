#include <catch2/catch.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "hdf5_handle.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "mbsflow/io/results_file.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "process_folder.hpp"
#include "superblock_edit.hpp"

using namespace mbsflow;
namespace fs = std::filesystem;

namespace {

fs::path temp_file(const std::string& name) { return test::process_folder("mbsflow_io_") / name; }

// The system at rest in its initial state at time t, with its energies.
Snapshot resting_snapshot(const MultibodySystem& sys, double t) {
  Snapshot s;
  s.t = t;
  s.state = sys.initial_state();
  s.energy = Energy{};
  return s;
}

Model chain_of(int bodies) {
  ChainParams p;
  p.bodies = bodies;
  return make_chain(p);
}

const RunInfo resumable_info{"{}", "rk4", 0.1, 0.0, 1.0, 1, "test"};

// A finished run's file: the system at rest at t = 0, 0.1, 0.2 and the coupling records
// given. Returns its run id, which a checkpoint of the run would hold.
std::string finished_run(const fs::path& file, const MultibodySystem& sys, const std::vector<CouplingRecord>& coupling = {}) {
  fs::remove(file);
  Hdf5Sink first(file.string(), FieldSet{}, resumable_info);
  first.begin(sys);
  for (double t : {0.0, 0.1, 0.2}) first.write(resting_snapshot(sys, t));
  if (!coupling.empty()) first.write_coupling(coupling);
  first.end();
  return first.identity();
}

Model small_train() {
  TrainParams p;
  p.wagons = 2;
  Model m = make_train(p);
  m.simulation.t_end = 0.5;
  m.simulation.step = 0.005;
  m.simulation.output_every = 1;  // 101 snapshots: several chunk rows of 16
  return m;
}

// Runs the model into an HDF5 file (through the asynchronous writer) and into memory.
std::pair<test::MemorySink, fs::path> run_both(const Model& m, const FieldSet& fields) {
  const fs::path file = temp_file(m.name + ".h5");
  const RunOptions o = options_from_model(m);
  {
    MultibodySystem sys(m);
    AsyncSink sink(std::make_unique<Hdf5Sink>(file.string(), fields, RunInfo{"{}", "rk4", o.step, o.t_start, o.t_end, 1, "test"}),
                   1 << 16);  // a small queue, so the writer really runs behind
    run_simulation(sys, o, &sink);
  }
  test::MemorySink memory;
  memory.wanted = {fields.joint_force, fields.energy};
  MultibodySystem sys(m);
  run_simulation(sys, o, &memory);
  return {std::move(memory), file};
}

// Every series of the file equals what the run handed to the memory sink, bit for bit.
void check_bitwise_equal(const Model& m, const test::MemorySink& memory, const ResultsFile& r) {
  const std::vector<double> t = r.time();
  REQUIRE(t.size() == memory.times.size());
  CHECK(t == memory.times);
  CHECK(r.body_names().size() == m.bodies.size());
  CHECK(r.joint_names().size() == m.joints.size());
  const StateLayout layout{static_cast<Eigen::Index>(m.bodies.size())};
  for (const BodyField& f : body_fields) {
    const std::vector<double> data = r.read(f.dataset);
    REQUIRE(data.size() == t.size() * m.bodies.size() * static_cast<std::size_t>(f.components));
    std::size_t k = 0;
    bool equal = true;
    for (const Eigen::VectorXd& y : memory.states)
      for (Eigen::Index b = 0; b < layout.bodies; ++b)
        for (int c = 0; c < f.components; ++c) equal = equal && data[k++] == y[(layout.*f.offset)(b) + c];
    INFO(f.dataset);
    CHECK(equal);
  }
  const std::vector<double> energy = r.read(energy_dataset), forces = r.read(joint_force_dataset);
  bool equal = true;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const Energy& e = *memory.snapshots[i].energy;
    equal = equal && energy[3 * i] == e.kinetic && energy[3 * i + 1] == e.gravity && energy[3 * i + 2] == e.elastic;
    const Eigen::VectorXd& w = memory.snapshots[i].joint_wrench;
    for (Eigen::Index k = 0; k < w.size(); ++k) equal = equal && forces[i * static_cast<std::size_t>(w.size()) + static_cast<std::size_t>(k)] == w[k];
  }
  CHECK(equal);
}


// Each end at its body's position plus the rotated attachment point (the ground's fixed).
void check_attachment_points(const Model& m, const ResultsFile& r) {
  const std::vector<double> t = r.time();
  const std::vector<std::uint64_t> shape = r.shape(joint_attachment_dataset);
  REQUIRE(shape == std::vector<std::uint64_t>{t.size(), m.joints.size(), 6});
  double worst = 0;
  for (std::size_t row : {std::size_t{0}, t.size() / 2, t.size() - 1}) {
    const std::vector<double> ends = r.read_row(joint_attachment_dataset, row);
    const std::vector<double> pos = r.read_row("/bodies/position", row), quat = r.read_row("/bodies/orientation", row);
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
      const Joint& joint = m.joints[j];
      for (int end = 0; end < 2; ++end) {
        const int body = end == 0 ? joint.body1 : joint.body2;
        const Vec3& p = end == 0 ? joint.point1 : joint.point2;
        Eigen::Vector3d expected(p[0], p[1], p[2]);
        if (body != ground) {
          const auto b = static_cast<std::size_t>(body);
          const Eigen::Quaterniond q(quat[4 * b], quat[4 * b + 1], quat[4 * b + 2], quat[4 * b + 3]);
          expected = Eigen::Vector3d(pos[3 * b], pos[3 * b + 1], pos[3 * b + 2]) + q * expected;
        }
        const Eigen::Vector3d written(ends.data() + 6 * j + 3 * end);
        worst = std::max(worst, (written - expected).norm());
      }
    }
  }
  CHECK(worst < 1e-12);
}

// The bodies' energies sum to the run's kinetic and gravity energies.
void check_body_energies(const Model& m, const ResultsFile& r) {
  REQUIRE(r.shape(body_energy_dataset) == std::vector<std::uint64_t>{r.time().size(), m.bodies.size(), 2});
  CHECK(r.dataset_string_attribute(body_energy_dataset, "units") == "J");
  double worst = 0;
  for (std::size_t row = 0; row < r.time().size(); ++row) {
    const std::vector<double> per_body = r.read_row(body_energy_dataset, row), total = r.read_row(energy_dataset, row);
    double kinetic = 0, gravity = 0, scale = 1;
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      kinetic += per_body[2 * i];
      gravity += per_body[2 * i + 1];
      scale += std::abs(per_body[2 * i]) + std::abs(per_body[2 * i + 1]);
    }
    worst = std::max({worst, std::abs(kinetic - total[0]) / scale, std::abs(gravity - total[1]) / scale});
  }
  CHECK(worst < 1e-13);
}

}  // namespace

TEST_CASE("HDF5 results read back bitwise equal to what was simulated", "[io]") {
  const Model m = small_train();
  auto [memory, file] = run_both(m, parse_fields("all"));
  const ResultsFile r(file.string());
  REQUIRE(r.time().size() == 101);
  check_bitwise_equal(m, memory, r);
  CHECK(r.body_names()[0] == "car0");
  CHECK(r.string_attribute("method").value() == "rk4");
  CHECK(r.number_attribute("step").value() == 0.005);
  CHECK(r.read_item("/bodies/position", 3).size() == 3 * r.time().size());
  fs::remove_all(file.parent_path());
}

// A row of more than 16 MiB is not buffered: each series' row is written as it is made, in
// slabs of 65536 items (the last one shorter), and must read back the same.
TEST_CASE("a model too large to buffer its rows writes them in slabs with the same content", "[io]") {
  ChainParams p;
  p.bodies = 150000;  // 19 numbers per body and joint: 22 MB a row, 3 slabs
  Model m = make_chain(p);
  m.simulation.step = 1e-5;
  m.simulation.t_end = 2e-5;
  m.simulation.output_every = 1;
  auto [memory, file] = run_both(m, parse_fields("all"));
  const ResultsFile r(file.string());
  REQUIRE(r.time().size() == 3);
  check_bitwise_equal(m, memory, r);
  check_attachment_points(m, r);
  check_body_energies(m, r);
  fs::remove_all(file.parent_path());
}

TEST_CASE("CSV export matches the HDF5 file exactly", "[io]") {
  const Model m = small_train();
  auto [memory, file] = run_both(m, parse_fields("position,velocity"));
  const ResultsFile r(file.string());
  const fs::path dir = file.parent_path() / "csv";
  const auto files = export_csv(r, dir.string(), {"bogie0f", "car1"});
  REQUIRE(files.size() == 2);
  std::ifstream in(dir / "bogie0f.csv");
  std::string header;
  std::getline(in, header);
  CHECK(header == "t [s],x [m],y [m],z [m],vx [m/s],vy [m/s],vz [m/s]");
  const std::vector<double> pos = r.read_item("/bodies/position", 1), vel = r.read_item("/bodies/velocity", 1);
  const std::vector<double> t = r.time();
  std::string line;
  std::size_t row = 0;
  bool equal = true;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
    REQUIRE(v.size() == 7);
    equal = equal && v[0] == t[row];
    for (int c = 0; c < 3; ++c) equal = equal && v[1 + c] == pos[3 * row + c] && v[4 + c] == vel[3 * row + c];
    ++row;
  }
  CHECK(equal);
  CHECK(row == t.size());
  CHECK_THROWS_AS(export_csv(r, dir.string(), {"nobody"}), InputError);
  fs::remove_all(file.parent_path());
}

TEST_CASE("opening something that is not a results file is an input error", "[io]") {
  const fs::path p = temp_file("not.h5");
  std::ofstream(p) << "hello";
  CHECK_THROWS_WITH(ResultsFile(p.string()), Catch::Contains("not an HDF5 file"));
  CHECK_THROWS_WITH(ResultsFile((p.parent_path() / "missing.h5").string()), Catch::Contains("no such results file"));
  fs::remove_all(p.parent_path());
}

TEST_CASE("field lists parse and reject unknown names", "[io]") {
  CHECK(fields_text(parse_fields("velocity,position")) == "position,velocity");
  CHECK(fields_text(parse_fields("all")) == "position,orientation,velocity,angular_velocity,energy,joint_force");
  CHECK_THROWS_WITH(parse_fields("position,acceleration"), Catch::Contains("unknown field 'acceleration'"));
}

TEST_CASE("every series carries its unit and the joints' attachment points follow their bodies", "[io]") {
  const Model m = small_train();
  auto [memory, file] = run_both(m, parse_fields("all"));
  const ResultsFile r(file.string());
  CHECK(r.dataset_string_attribute("/time", "units") == "s");
  for (const BodyField& f : body_fields) CHECK(r.dataset_string_attribute(f.dataset, "units") == std::string(f.unit));
  CHECK(r.dataset_string_attribute(energy_dataset, "units") == "J");
  CHECK(r.dataset_string_attribute(joint_force_dataset, "units") == "N, N m");
  CHECK(r.dataset_string_attribute(joint_attachment_dataset, "units") == "m");
  check_attachment_points(m, r);
}

TEST_CASE("the bodies' energies sum to the run's kinetic and gravity energies", "[io]") {
  Model m = small_train();
  Vec6 inertia = m.bodies[1].inertia;  // products of inertia too
  const double small = 0.01 * std::min({inertia[0], inertia[1], inertia[2]});
  inertia[3] = small;
  inertia[4] = -small;
  inertia[5] = 0.5 * small;
  m.bodies[1].inertia = inertia;
  auto [memory, file] = run_both(m, parse_fields("all"));
  const ResultsFile r(file.string());
  check_body_energies(m, r);
}

TEST_CASE("the model text is kept whole in /model and files with the old model attribute still read", "[io]") {
  Model m = small_train();
  m.simulation.t_end = 0.02;
  // Long (beyond what an attribute's object header holds) and not plain ASCII.
  m.name = "z\xC3\xBCge-" + std::string(100000, 'x');
  const std::string json = model_to_json(m);
  const fs::path file = temp_file("model_text.h5");
  const RunOptions o = options_from_model(m);
  {
    MultibodySystem sys(m);
    AsyncSink sink(std::make_unique<Hdf5Sink>(file.string(), FieldSet{}, RunInfo{json, "rk4", o.step, o.t_start, o.t_end, 1, "test"}));
    run_simulation(sys, o, &sink);
  }
  const ResultsFile r(file.string());
  CHECK(r.model_text() == json);
  CHECK(read_model_text(*r.model_text(), "back").name == m.name);
  CHECK(!r.string_attribute("model"));
  // A file of an earlier version: the model as a root attribute of variable length.
  const fs::path old = temp_file("model_attribute.h5");
  {
    const hid_t f = H5Fcreate(old.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    REQUIRE(f >= 0);
    mbsflow::h5::write_string_attribute(f, "model", "{\"old\": true}");
    CHECK(mbsflow::h5::read_text_dataset(f, "model") == std::nullopt);
    CHECK(mbsflow::h5::read_string_attribute(f, "model") == std::string("{\"old\": true}"));
    H5Fclose(f);
  }
  fs::remove(file);
  fs::remove(old);
}

TEST_CASE("a prepared results file holds the model's text before the run begins and nothing is left if it never does",
          "[io]") {
  Model m = small_train();
  m.simulation.t_end = 0.02;
  const std::string json = model_to_json(m);
  const fs::path file = temp_file("prepared.h5"), part = file.string() + ".part";
  const RunOptions o = options_from_model(m);
  const RunInfo info{json, "rk4", o.step, o.t_start, o.t_end, 1, "test"};
  SECTION("prepared, then run") {
    auto h5 = std::make_unique<Hdf5Sink>(file.string(), FieldSet{}, info);
    h5->prepare();
    CHECK(fs::exists(part));
    CHECK(!fs::exists(file));
    // The file is locked from here on: a second run to the same path is refused.
    Hdf5Sink second(file.string(), FieldSet{}, info);
    CHECK_THROWS_AS(second.prepare(), InputError);
    {
      MultibodySystem sys(m);
      AsyncSink sink(std::move(h5));
      run_simulation(sys, o, &sink);
    }
    CHECK(!fs::exists(part));
    const ResultsFile r(file.string());
    CHECK(r.model_text() == json);
    CHECK(r.time().size() == 5);
  }
  SECTION("prepared, never begun (the run's set-up failed)") {
    {
      Hdf5Sink h5(file.string(), FieldSet{}, info);
      h5.prepare();
      REQUIRE(fs::exists(part));
    }
    CHECK(!fs::exists(part));
    CHECK(!fs::exists(file));
  }
  fs::remove(file);
}

TEST_CASE("a run resumed from a file whose run was killed as it closed writes its coupling records in their place", "[io]") {
  // A checkpointed run killed after end() wrote /coupling leaves it in the file; the
  // resumed run writes them again at its end.
  const Model m = chain_of(3);
  const MultibodySystem sys(m);
  const fs::path file = temp_file("coupling_resumed.h5");
  const auto records = [](long n) {
    std::vector<CouplingRecord> r(static_cast<std::size_t>(n));
    for (long i = 0; i < n; ++i) r[static_cast<std::size_t>(i)] = {i + 1, 0.1 * i, 0.1 * (i + 1), 1e-9, 1e-8, 0};
    return r;
  };
  const std::string identity = finished_run(file, sys, records(2));
  Hdf5Sink resumed(file.string(), FieldSet{}, resumable_info);
  resumed.resume(sys, 2, identity);
  for (double t : {0.2, 0.3}) resumed.write(resting_snapshot(sys, t));
  resumed.write_coupling(records(3));
  REQUIRE_NOTHROW(resumed.end());
  const ResultsFile r(file.string());
  CHECK(r.time() == std::vector<double>{0.0, 0.1, 0.2, 0.3});
  CHECK(r.read("/coupling/index") == std::vector<double>{1.0, 2.0, 3.0});
  CHECK(r.read("/coupling/t_end").back() == 0.1 * 3);
}

TEST_CASE("a results file whose writer was killed while writing its end is still recognised and read", "[io]") {
  // end() writes the file's last parts outside SWMR mode; a writer killed there leaves
  // the file marked open for writing, which plain and SWMR readers both refuse.
  ChainParams p;
  p.bodies = 2;
  const Model m = make_chain(p);
  const MultibodySystem sys(m);
  const fs::path file = temp_file("killed_in_end.h5");
  fs::remove(file);
  {
    Hdf5Sink sink(file.string(), FieldSet{}, RunInfo{"{}", "rk4", 0.1, 0.0, 1.0, 1, "test"});
    sink.begin(sys);
    Snapshot s;
    s.state = sys.initial_state();
    s.energy = Energy{};
    sink.write(std::move(s));
    sink.end();
  }
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST);
    const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, fapl);
    if (f >= 0) H5Fflush(f, H5F_SCOPE_GLOBAL);
    ::raise(SIGKILL);  // never closes it
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  REQUIRE(WIFSIGNALED(status));
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  REQUIRE(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT) < 0);  // the mark is there
  CHECK(is_mbsflow_results_file(file.string()));
  CHECK_NOTHROW(check_output_path(file.string(), {}));
  const ResultsFile r(file.string());
  CHECK(r.time().size() == 1);
  fs::remove(file);
}

TEST_CASE("a results file whose writer was killed before it grew the file to its recorded end is mended to resume", "[io]") {
  // Killed while closing in end(): the superblock records the file's new end, the file is
  // still shorter, and HDF5 refuses it as cut short ("truncated file"); seen once in 65
  // kill -9 and --resume cycles of a 1000-body chain, 415 bytes short.
  const Model m = chain_of(3);
  const MultibodySystem sys(m);
  const fs::path file = temp_file("killed_before_grown.h5");
  const std::string identity = finished_run(file, sys);
  const auto size = fs::file_size(file);
  REQUIRE(test::read_superblock(file.string()).end() == size);

  // Closed cleanly and then cut short (a copy that ended early): left as it is.
  test::rewrite_superblock(file.string(), 0, size + 415);
  CHECK_NOTHROW(mend_results_file_to_resume(file.string()));
  CHECK(fs::file_size(file) == size);
  CHECK(!is_mbsflow_results_file(file.string()));

  // The killed writer's: refused by HDF5 as it is, grown and resumed.
  test::rewrite_superblock(file.string(), 1, size + 415);
  CHECK(!is_mbsflow_results_file(file.string()));
  mend_results_file_to_resume(file.string());
  CHECK(fs::file_size(file) == size + 415);
  CHECK(is_mbsflow_results_file(file.string()));
  Hdf5Sink resumed(file.string(), FieldSet{}, resumable_info);
  resumed.resume(sys, 2, identity);
  for (double t : {0.2, 0.3}) resumed.write(resting_snapshot(sys, t));
  REQUIRE_NOTHROW(resumed.end());
  CHECK(ResultsFile(file.string()).time() == std::vector<double>{0.0, 0.1, 0.2, 0.3});

  // The sink grows it too, for a library caller that resumes without the CLI's mending.
  test::rewrite_superblock(file.string(), 1, fs::file_size(file) + 100);
  Hdf5Sink again(file.string(), FieldSet{}, resumable_info);
  REQUIRE_NOTHROW(again.resume(sys, 4, resumed.identity()));
  REQUIRE_NOTHROW(again.end());
  CHECK(ResultsFile(file.string()).time().size() == 4);
  fs::remove(file);
}
