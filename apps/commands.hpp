#pragma once
// Each subcommand registers its options and returns what to do once parsing is done.
#include <CLI/CLI.hpp>
#include <functional>

namespace mbsflow::cli {

using Action = std::function<int()>;  // returns the exit code

Action add_run(CLI::App& app);
Action add_generate(CLI::App& app);
Action add_bench(CLI::App& app);

}  // namespace mbsflow::cli
