#pragma once
// mbsflow run --slurm: the run of a Slurm step, every task started by srun with the same
// command line. Task 0 coordinates and writes the results; the others serve as workers.
#include <string>

#include "mbsflow/io/slurm.hpp"

namespace mbsflow::cli {

struct SlurmLaunch {
  SlurmStep step;
  int base_port = 0;
  CurveKeyPair keys;
};

// From this task's environment; port 0 takes the job's default; key_stem "" takes
// $HOME/.mbsflow/cluster (STEM.key, made once with `mbsflow keygen STEM`).
SlurmLaunch slurm_launch(int port, const std::string& key_stem);
// A task other than 0: serves the run as a worker; returns the exit code.
int serve_slurm_task(const SlurmLaunch& s, int threads, bool quiet);

}  // namespace mbsflow::cli
