#pragma once
// Each subcommand registers its options and returns what to do once parsing is done.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow::cli {

using Action = std::function<int()>;  // returns the exit code

Action add_run(CLI::App& app);
Action add_generate(CLI::App& app);
Action add_partition(CLI::App& app);
Action add_bench(CLI::App& app);
Action add_info(CLI::App& app);
Action add_export(CLI::App& app);
Action add_worker(CLI::App& app);
Action add_ode(CLI::App& app);
Action add_modes(CLI::App& app);  // cmd_modes.cpp
Action add_frf(CLI::App& app);
Action add_keygen(CLI::App& app);
Action add_view(CLI::App& app);
Action add_plot(CLI::App& app);
Action add_plan(CLI::App& app);
Action add_reduce(CLI::App& app);  // cmd_reduce.cpp

// `mbsflow worker` once its options are read; also what a worker task of `run --slurm` does.
int serve_worker_command(WorkerOptions options, bool quiet);

// How the CLI names a setting that a library message mentions (mbsflow/error.hpp): its
// flag, "--step 1e-05"; the per-submodel methods are --submodel-methods.
std::string flag_for(const std::string& setting, const std::string* value);
// " (did you mean NAME?)" for the command nearest to a mistyped one, or "".
std::string closest_name(const std::string& given, const std::vector<std::pair<CLI::App*, Action>>& commands);

// The command line as typed, for the results file.
const std::string& invocation();
const std::vector<std::string>& invocation_arguments();  // argv as given
void set_invocation(int argc, char** argv);

}  // namespace mbsflow::cli
