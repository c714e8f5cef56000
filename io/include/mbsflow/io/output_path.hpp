#pragma once
// Where a results file may be written: a path that holds nothing yet, or an mbsflow
// results file (of `run` or `ode`), which a new run replaces. Anything else there (the
// model, a CSV, a folder, a device, a FIFO) is refused before anything is opened, so a
// typo in -o never costs a user a file; `force` lets a run replace another regular file.
#include <string>
#include <vector>

namespace mbsflow {

struct OutputPathRules {
  std::vector<std::string> inputs;  // files the run reads (the model, a partition file): never written over
  bool force = false;               // replace a regular file that is not a results file
  std::string flag = "-o";          // how the front end names the setting, for the messages
};

// InputError naming the path, what is there and what to do instead.
void check_output_path(const std::string& path, const OutputPathRules& rules = {});

// Whether the file at path is an HDF5 file that mbsflow wrote (its root has the
// attribute mbsflow_version). False for anything else, a missing file included.
bool is_mbsflow_results_file(const std::string& path);

// Before a run goes on writing its results file from a checkpoint: a file whose writer was
// killed while closing it, which HDF5 would refuse as cut short, is grown to the end its
// superblock records (io/src/killed_writer.hpp says why nothing kept is lost). Nothing
// happens to a missing file; InputError where another run is writing it.
void mend_results_file_to_resume(const std::string& path);

}  // namespace mbsflow
