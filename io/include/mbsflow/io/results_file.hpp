#pragma once
// Reads a results file written by Hdf5Sink.
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
  bool has(const std::string& dataset) const;
  std::vector<std::uint64_t> shape(const std::string& dataset) const;  // empty if absent

  std::vector<double> time() const;
  std::vector<std::string> body_names() const;
  std::vector<std::string> joint_names() const;
  // A whole float64 dataset, row-major.
  std::vector<double> read(const std::string& dataset) const;
  // T x k values of one body (or joint) from a T x N x k dataset, row-major.
  std::vector<double> read_item(const std::string& dataset, std::size_t index) const;
  std::uintmax_t size_bytes() const;

 private:
  std::vector<std::string> names(const char* dataset) const;
  std::string path_;
  std::int64_t file_ = -1;  // hid_t
};

// One CSV file per body in dir (BODY.csv: t and every body field present), for the named
// bodies or all. Returns the files written.
std::vector<std::string> export_csv(const ResultsFile& results, const std::string& dir,
                                    const std::vector<std::string>& bodies);

}  // namespace mbsflow
