// mbsflow view FILE.h5 [-o FILE.html]: the motion as one HTML page that plays in a browser.
#include <cstdio>
#include <fstream>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/results_file.hpp"
#include "viewer_page.hpp"

namespace mbsflow::cli {
namespace {

struct ViewArgs {
  std::string file, output;
  ViewerSettings settings;
};

int view(const ViewArgs& a) {
  const ResultsFile r(a.file);
  const ViewerPage page = viewer_page(r, a.settings);
  const std::string out = a.output.empty() ? a.file.substr(0, a.file.find_last_of('.')) + ".html" : a.output;
  std::ofstream o(out);
  o << page.html;
  if (!o.flush()) throw Error(out + ": cannot write the page");
  std::fprintf(stderr, "mbsflow: wrote %s (%.1f MB): %ld frames%s; open it in a browser\n", out.c_str(),
               static_cast<double>(page.html.size()) / 1e6, page.frames,
               page.stride > 1 ? (", every " + std::to_string(page.stride) + "th snapshot").c_str() : "");
  return 0;
}

}  // namespace

Action add_view(CLI::App& app) {
  auto a = std::make_shared<ViewArgs>();
  CLI::App* sub = app.add_subcommand("view", "Write the motion as one self-contained HTML page (three.js, no network): bodies as "
                                             "ellipsoids from their inertia, joints as lines, play, seek, speed, orbit, colour");
  sub->add_option("file", a->file, "Results file (.h5) of mbsflow run")->required();
  sub->add_option("-o,--output", a->output, "Page to write (default: FILE.html)");
  sub->add_option("--max-frames", a->settings.max_frames, "Snapshots shown at most, evenly spread (default 1000)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-mb", a->settings.max_megabytes, "Bound on the motion data in the page, MB (default 200)")
      ->check(CLI::PositiveNumber);
  return [a] { return view(*a); };
}

}  // namespace mbsflow::cli
