// mbsflow plot FILE.h5: the plot script (scripts/plot.py, Debian's python3 with h5py and
// matplotlib) on a results file, finished or being written (--follow).
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "shared_files.hpp"

namespace mbsflow::cli {
namespace {

struct PlotArgs {
  std::string file, output, bodies;
  bool follow = false;
  double interval = 2.0;
};

int plot(const PlotArgs& a) {
  const std::string script = shared_file("plot.py");
  std::vector<std::string> args{"/usr/bin/python3", script, a.file};
  if (!a.output.empty()) args.insert(args.end(), {"-o", a.output});
  if (!a.bodies.empty()) args.insert(args.end(), {"--bodies", a.bodies});
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
  sub->add_option("--bodies", a->bodies, "Comma-separated body names (default: up to 5 spread over the model)");
  sub->add_flag("--follow", a->follow, "Redraw every --interval seconds while a run writes the file, until it ends");
  sub->add_option("--interval", a->interval, "--follow: seconds between pictures (default 2)")->check(CLI::PositiveNumber);
  return [a] { return plot(*a); };
}

}  // namespace mbsflow::cli
