#pragma once
// Reads a results file: of a multibody run (written by Hdf5Sink) or of an ODE run
// (mbsflow ode, write_ode_results).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbsflow {

class ResultsFile {
 public:
  explicit ResultsFile(const std::string& path);  // InputError if it is no readable mbsflow results file
  ~ResultsFile();
  ResultsFile(ResultsFile&&) noexcept;
  ResultsFile& operator=(ResultsFile&&) noexcept;

  const std::string& path() const { return path_; }
  std::optional<std::string> string_attribute(const std::string& name) const;
  std::optional<double> number_attribute(const std::string& name) const;
  std::optional<std::string> dataset_string_attribute(const std::string& dataset, const std::string& name) const;
  // The model the run integrated (JSON, as model_to_json writes it): the string dataset
  // /model, or the root attribute "model" of files written before 2026-11-24.
  std::optional<std::string> model_text() const;
  bool has(const std::string& dataset) const;
  std::vector<std::uint64_t> shape(const std::string& dataset) const;  // empty if absent

  bool ode() const { return ode_; }  // the results of mbsflow ode: /solution and /steps
  bool modes() const { return modes_; }  // the results of mbsflow modes: /modes, /equilibrium
  // Opened as SWMR reader: a run is writing the file (or was killed while it did).
  bool live() const { return live_; }
  std::vector<double> time() const;  // snapshot times, or the ODE solution's points
  std::vector<std::string> body_names() const;
  std::vector<std::string> joint_names() const;
  // A whole float64 dataset, row-major.
  std::vector<double> read(const std::string& dataset) const;
  // T x k values of one body (or joint) from a T x N x k dataset, row-major.
  std::vector<double> read_item(const std::string& dataset, std::size_t index) const;
  // Row `row` of a T x ... dataset: its values at one time, row-major.
  std::vector<double> read_row(const std::string& dataset, std::size_t row) const;
  std::uintmax_t size_bytes() const;

 private:
  std::vector<std::string> names(const char* dataset) const;
  std::string path_;
  std::int64_t file_ = -1;  // hid_t
  bool ode_ = false;
  bool modes_ = false;
  bool live_ = false;
};

// CSV files in dir, headers with units in brackets ("x [m]"). A run: one file per body
// (BODY.csv: t and every body field present), for the named bodies or all; for all, also
// energy.csv and one file per joint (joint_NAME.csv: force, torque, motor effort and
// attachment points, those present). An ODE run: solution.csv (t and each kept component)
// and steps.csv (every step tried); `bodies` must be empty. Returns the files written.
std::vector<std::string> export_csv(const ResultsFile& results, const std::string& dir,
                                    const std::vector<std::string>& bodies);

}  // namespace mbsflow
