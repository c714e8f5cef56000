#pragma once
// Snapshots as CSV, one row per body per output instant (the HDF5 writer replaces
// this as the main output; CSV stays for quick looks and small models).
#include <fstream>
#include <string>

#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow {

class CsvSink : public ResultSink {
 public:
  explicit CsvSink(std::string path) : path_(std::move(path)) {}
  void begin(const MultibodySystem& system) override;
  void write(double t, const Eigen::VectorXd& y) override;
  void end() override;

 private:
  std::string path_;
  std::ofstream out_;
  const MultibodySystem* system_ = nullptr;
};

}  // namespace mbsflow
