// mbsflow modes and mbsflow frf from the command line: the working point, the table, the
// results file, the frequency response's CSV and state-space matrices, and the errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <numbers>

#include "cli_support.hpp"
#include "mbsflow/io/results_file.hpp"

using namespace mbsflow::test;

namespace {

const char* pendulum = R"({"name": "pendulum", "gravity": [0, -9.81, 0],
  "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.02, 0.02, 0.02], "position": [1, 0, 0]}],
  "joints": [{"name": "pivot", "type": "revolute", "body1": "ground", "body2": "bob",
              "point1": [0, 0, 0], "point2": [-1, 0, 0], "axis1": [0, 0, 1]}]})";

const char* mount = R"({"name": "mount", "gravity": [0, 0, 0],
  "bodies": [{"name": "block", "mass": 2.0, "inertia": [0.3, 0.5, 0.7], "position": [0, 0, 0]}],
  "joints": [{"name": "pad", "type": "bushing", "body1": "ground", "body2": "block", "point1": [0, 0, 0], "point2": [0, 0, 0],
              "stiffness": [800, 1800, 3200, 30, 80, 140], "damping": [4, 1, 1, 0.1, 0.1, 0.1]}]})";

}  // namespace

TEST_CASE("modes: a pendulum released level is linearised hanging, one mode, kept in a results file", "[apps][modes]") {
  const fs::path d = scratch("modes-pendulum");
  const std::string dir = d.string();
  std::ofstream(d / "pendulum.json") << pendulum;
  const Result r = run("modes pendulum.json -o modes.h5", dir, true);
  INFO(r.err << r.out);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("static equilibrium in ") != std::string::npos);
  CHECK(r.out.find("1 degree of freedom") != std::string::npos);
  const mbsflow::ResultsFile f((d / "modes.h5").string());
  REQUIRE(f.modes());
  const std::vector<double> hz = f.read("/modes/frequency");
  REQUIRE(hz.size() == 1);
  CHECK(hz[0] == Approx(std::sqrt(9.81 / (1.0 + 0.02)) / (2 * std::numbers::pi)).epsilon(1e-8));
  const std::vector<double> position = f.read("/equilibrium/position");
  CHECK(position[1] == Approx(-1.0).epsilon(1e-8));  // hanging
  CHECK(f.body_names() == std::vector<std::string>{"bob"});
  CHECK(*f.dataset_string_attribute("/modes/frequency", "units") == "Hz");
  const Result info = run("info modes.h5", dir, true);
  CHECK(info.code == 0);
  CHECK(info.out.find("1 mode about the static equilibrium") != std::string::npos);
  // The ParaView sidecar beside it, and the modes as CSV.
  CHECK(r.err.find("ParaView animates them from modes.xdmf (16 frames a period") != std::string::npos);
  CHECK(fs::exists(d / "modes.xdmf"));
  REQUIRE(run("export modes.h5 --csv csv", dir, true).code == 0);
  std::ifstream table(d / "csv" / "modes.csv"), bob(d / "csv" / "bob.csv");
  std::string header, row;
  REQUIRE(std::getline(table, header));
  CHECK(header.rfind("mode,frequency [Hz],damping_ratio", 0) == 0);
  REQUIRE(std::getline(table, row));
  CHECK(std::stod(row.substr(row.find(',') + 1)) == hz[0]);  // to full precision
  CHECK(!std::getline(table, row));  // one mode
  REQUIRE(std::getline(bob, header));
  CHECK(header == "mode,x,y,z,rx,ry,rz,x_imag,y_imag,z_imag,rx_imag,ry_imag,rz_imag,kinetic_share,strain_share");
  // At the state given: level, the rod carries no tension and the pendulum has no stiffness.
  const Result level = run("modes pendulum.json --at-initial --undamped", dir, true);
  CHECK(level.code == 0);
  CHECK(level.out.find("rigid-body motion") != std::string::npos);
  fs::remove_all(d.parent_path());
}

TEST_CASE("modes: a run's snapshot as the working point, and refusals that name what is wrong", "[apps][modes]") {
  const fs::path d = scratch("modes-errors");
  const std::string dir = d.string();
  std::ofstream(d / "pendulum.json") << pendulum;
  std::ofstream(d / "falling.json") << R"({"name": "falling", "gravity": [0, -9.81, 0],
    "bodies": [{"name": "stone", "mass": 1.0, "inertia": [0.1, 0.1, 0.1], "position": [0, 0, 0]}], "joints": []})";
  REQUIRE(run("run pendulum.json --t-end 0.5 -q -o run.h5", dir).code == 0);
  const Result at = run("modes pendulum.json --at run.h5 --time 0.5", dir, true);
  INFO(at.err);
  CHECK(at.code == 0);
  CHECK(at.out.find("linearised at the t = 0.5 s of run.h5") != std::string::npos);
  const Result falling = run("modes falling.json", dir);
  CHECK(falling.code == 1);
  CHECK(falling.err.find("body 'stone' does not settle") != std::string::npos);
  const Result over = run("modes pendulum.json -o pendulum.json", dir);
  CHECK(over.code == 2);
  CHECK(over.err.find("is the input file") != std::string::npos);
  CHECK(run("modes pendulum.json --at run.h5 --at-initial", dir).code == 2);
  fs::remove_all(d.parent_path());
}

TEST_CASE("modes: the sparse solver says so before it turns to Spectra's restarts", "[apps][modes]") {
  // The flyball governor's augmented pencil leaves values under the rounding of the
  // Arnoldi relation (analysis/src/arnoldi.cpp): the restarted solver takes over.
  const std::string model = std::string(MBSFLOW_SOURCE) + "/examples/models/iftomm_a05_flyball_governor.json";
  const Result r = run("modes '" + model + "' --solver sparse -n 2", ".", true);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.err.find("Spectra's restarted Arnoldi takes over") != std::string::npos);
  CHECK(r.out.find("Spectra, restarted Arnoldi") != std::string::npos);
  CHECK(r.out.find("0.569219") != std::string::npos);  // the governor's swing, as the dense solver finds it
  const Result quiet = run("modes '" + model + "' --solver sparse -n 2 -q");
  CHECK(quiet.err.find("takes over") == std::string::npos);
}

TEST_CASE("frf: a damped oscillator's magnitude and phase in CSV, and its state-space matrices", "[apps][frf]") {
  const fs::path d = scratch("frf");
  const std::string dir = d.string();
  std::ofstream(d / "mount.json") << mount;
  const Result r = run("frf mount.json --input block:fx --output block:x --output block:ay --from 1 --to 10 --points 5 "
                       "-o frf.csv --state-space ss --at-initial",
                       dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::ifstream csv(d / "frf.csv");
  std::string header;
  std::getline(csv, header);
  CHECK(header == "frequency_hz,block:x/block:fx magnitude,block:x/block:fx phase_deg,block:ay/block:fx magnitude,"
                  "block:ay/block:fx phase_deg");
  int rows = 0;
  for (std::string line; std::getline(csv, line); ++rows) {
    const std::vector<std::string> c = csv_cells(line);
    REQUIRE(c.size() == 5);
    const double w = 2 * std::numbers::pi * std::stod(c[0]);
    const std::complex<double> h = 1.0 / std::complex<double>(800.0 - 2.0 * w * w, 4.0 * w);
    CHECK(std::stod(c[1]) == Approx(std::abs(h)).epsilon(1e-8));
    CHECK(std::stod(c[2]) == Approx(std::arg(h) * 180 / std::numbers::pi).epsilon(1e-8));
    CHECK(std::stod(c[3]) < 1e-12);  // no sideways response
  }
  CHECK(rows == 5);
  for (const char* m : {"A", "B", "C", "D"}) CHECK(read_text(d / "ss" / (std::string(m) + ".mtx")).rfind("%%MatrixMarket", 0) == 0);
  const Result bad = run("frf mount.json --input block:fq --output block:x", dir);
  CHECK(bad.code == 2);
  CHECK(bad.err.find("'fq' is not one of fx, fy, fz, tx, ty, tz") != std::string::npos);
  fs::remove_all(d.parent_path());
}
