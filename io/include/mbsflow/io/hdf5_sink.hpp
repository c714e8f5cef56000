#pragma once
// Results as one HDF5 file per run, in global body order, plus an XDMF sidecar:
//   /time (T), /bodies/names (N), /bodies/{position,orientation,velocity,angular_velocity}
//   (T x N x k), /energy (T x 3), /joints/names (J), /joints/force (T x J x 6), and for
//   loosely coupled runs /coupling/{index,t_start,t_end,position_error,velocity_error,lag}
//   (one row per macro step);
// chunked and extendible along time, run settings and a random run_id as attributes of
// the root group.
// Snapshots are buffered into whole chunk rows, so HDF5 writes full chunks.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mbsflow/io/result_fields.hpp"
#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow {

struct RunInfo {
  std::string model_json;
  std::string method;
  double step = 0.0;
  double t_start = 0.0, t_end = 0.0;
  int output_every = 1;
  std::string command_line;
  double output_interval = 0.0;  // s; 0: the grid is output_every steps
};

// Writes a run's results. The file is locked against a second run (which is refused, not
// allowed to truncate it), its layout is flushed at creation and its rows at least every
// second, so a killed run leaves a file that reads up to its last flush. While the run
// goes, the file is in HDF5's single-writer/multiple-reader mode (SWMR): readers open it
// with H5F_ACC_SWMR_READ (h5py: swmr=True; ResultsFile does) and see it grow.
class Hdf5Sink : public ResultSink {
 public:
  static constexpr double flush_interval_s = 1.0;
  Hdf5Sink(std::string path, FieldSet fields, RunInfo info);
  ~Hdf5Sink() override;
  SnapshotContent content() const override { return {fields_.joint_force, fields_.energy}; }
  // Creates the file now (under its .part name, locked) and writes the model's text and
  // the run's settings, so the caller need not hold the text (half a gigabyte for a
  // million bodies) while the run is set up; begin() lays out the rest. Not for a run
  // that resumes the file. Without it, begin() does it all.
  void prepare();
  void begin(const MultibodySystem& system) override;
  void write(Snapshot&& snapshot) override;
  void write_coupling(const std::vector<CouplingRecord>& records) override;
  void end() override;  // writes what is buffered and the XDMF sidecar, closes the file
  void sync() override;  // writes what is buffered and flushes the file
  std::string identity() const override { return identity_; }  // the file's run_id attribute
  // Opens the file again, keeps its first `snapshots` rows and goes on after them.
  void resume(const MultibodySystem& system, long snapshots, const std::string& identity) override;
  const std::string& path() const { return path_; }
  long snapshots_written() const { return rows_written_; }

 private:
  struct File;  // HDF5 handles and the writer lock, in the .cpp
  void flush();
  void lay_out(File& f, const MultibodySystem& system, bool make);
  void lay_out_and_publish(std::unique_ptr<File> f, const MultibodySystem& system);  // begin()'s work
  std::unique_ptr<File> create();
  void write_header(File& f, const std::string& making);
  std::string part_path() const { return path_ + ".part"; }

  std::string path_;
  FieldSet fields_;
  RunInfo info_;
  std::unique_ptr<File> file_;
  std::unique_ptr<File> created_;  // prepared, not yet begun
  const MultibodySystem* system_ = nullptr;
  std::string identity_;
  std::vector<CouplingRecord> coupling_;  // written by end()
  long rows_written_ = 0;
  double last_flush_ = 0.0;  // steady-clock seconds: buffered rows are written at least every flush_interval_s
};

// Path of the XDMF sidecar of a results file: FILE.h5 -> FILE.xdmf.
std::string xdmf_path(const std::string& h5_path);

}  // namespace mbsflow
