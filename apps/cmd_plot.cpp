// mbsflow plot FILE.h5: the plot script (scripts/plot.py, Debian's python3 with h5py and
// matplotlib) on a results file, finished or being written (--follow).
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/output_path.hpp"
#include "shared_files.hpp"

namespace mbsflow::cli {
namespace {

struct PlotArgs {
  std::string file, output;
  std::vector<std::string> bodies;
  bool follow = false;
  double interval = 2.0;
};

// A results file to read, said in one line like info and export do (plot.py would print a
// traceback); a file that a run has yet to create is waited for only with --follow.
void check_results_input(const PlotArgs& a) {
  if (a.follow && !std::filesystem::exists(a.file)) return;
  std::error_code ec;
  if (!std::filesystem::exists(a.file, ec)) throw InputError(a.file + ": cannot open the results file");
  if (!is_mbsflow_results_file(a.file))
    throw InputError(a.file + ": not an mbsflow results file (mbsflow run -o FILE.h5 or mbsflow ode -o FILE.h5 writes one)");
  if (!a.output.empty()) check_output_path(a.output, {{a.file}, true});
}

int plot(const PlotArgs& a) {
  check_results_input(a);
  const std::string script = shared_file("plot.py");
  std::vector<std::string> args{"/usr/bin/python3", script, a.file};
  if (!a.output.empty()) args.insert(args.end(), {"-o", a.output});
  if (!a.bodies.empty()) {
    std::string list;
    for (const std::string& b : a.bodies) list += (list.empty() ? "" : ",") + b;
    args.insert(args.end(), {"--bodies", list});
  }
  if (a.follow) args.insert(args.end(), {"--follow", "--interval", std::to_string(a.interval)});
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  throw Error(std::string("mbsflow plot: cannot start /usr/bin/python3: ") + std::strerror(errno) +
              " (Debian's python3 with python3-h5py and python3-matplotlib)");
}

}  // namespace

Action add_plot(CLI::App& app) {
  auto a = std::make_shared<PlotArgs>();
  CLI::App* sub = app.add_subcommand("plot", "Draw a results file as PNG (trajectories, energies, joint reactions; for mbsflow ode "
                                             "the solution, error and steps), also while a run writes it");
  sub->add_option("file", a->file, "Results file (.h5)")->required();
  sub->add_option("-o,--output", a->output, "PNG to write (default: FILE.png)");
  sub->add_option("--bodies", a->bodies, "Bodies to draw, comma-separated or one per option (default: up to 5 spread over the model)")
      ->delimiter(',');
  sub->add_flag("--follow", a->follow, "Redraw every --interval seconds while a run writes the file, until it ends");
  sub->add_option("--interval", a->interval, "--follow: seconds between pictures (default 2)")->check(CLI::PositiveNumber);
  return [a] { return plot(*a); };
}

}  // namespace mbsflow::cli
