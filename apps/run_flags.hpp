#pragma once
// mbsflow run's flags, one per setting of run_settings() that the command line takes.
#include <CLI/CLI.hpp>

#include "mbsflow/runtime/run_settings.hpp"

namespace mbsflow::cli {

// Adds a flag for each setting of the command line to `sub`, writing into `request`; its
// range or choices checked as the flag is read, its help from the declaration.
void add_run_settings(CLI::App* sub, RunRequest& request);

}  // namespace mbsflow::cli
