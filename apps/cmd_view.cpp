// mbsflow view FILE.h5 [-o FILE.html | --serve]: the motion as one HTML page that plays in a
// browser, written to a file or served (for a live run, made afresh at each reload).
#include <atomic>
#include <cstdio>
#include <fstream>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/words.hpp"
#include "mbsflow/io/results_file.hpp"
#include "page_server.hpp"
#include "mbsflow/runtime/stop_signals.hpp"
#include "viewer_page.hpp"

namespace mbsflow::cli {
namespace {

struct ViewArgs {
  std::string file, output;
  ViewerSettings settings;
  bool serve = false;
  std::string host = "127.0.0.1";
  int port = 8000;
  double interval = 3;
};

// The page made afresh from the file for each request: a live run's shows its snapshots
// so far and reloads itself.
int serve(const ViewArgs& a) {
  PageServer server = open_page_server(a.host, a.port);
  std::printf("mbsflow view: serving %s at http://%s:%d/ (Ctrl-C stops)\n", a.file.c_str(), a.host.c_str(), server.port);
  std::fflush(stdout);
  const std::atomic<bool>* stop = install_stop_handlers();
  serve_pages(server, [&] {
    const ResultsFile r(a.file);
    ViewerSettings settings = a.settings;
    settings.refresh_seconds = r.live() ? a.interval : 0;
    return viewer_page(r, settings).html;
  }, stop);
  return 0;
}

int view(const ViewArgs& a) {
  if (a.serve) return serve(a);
  const ResultsFile r(a.file);
  const ViewerPage page = viewer_page(r, a.settings);
  const std::string out = a.output.empty() ? a.file.substr(0, a.file.find_last_of('.')) + ".html" : a.output;
  check_output_path(out, {{a.file}, true});  // a page replaces a file, never the results, a folder or a device
  std::ofstream o(out);
  o << page.html;
  if (!o.flush()) throw Error(out + ": cannot write the page");
  std::fprintf(stderr, "mbsflow: wrote %s (%.1f MB): %s%ld frames%s; open it in a browser\n", out.c_str(),
               static_cast<double>(page.html.size()) / 1e6,
               r.modes() ? ("mode " + std::to_string(a.settings.mode) + " over one period, ").c_str() : "", page.frames,
               page.stride > 1 ? (", every " + ordinal(page.stride) + " snapshot").c_str() : "");
  return 0;
}

}  // namespace

Action add_view(CLI::App& app) {
  auto a = std::make_shared<ViewArgs>();
  CLI::App* sub = app.add_subcommand("view", "Write the motion as one self-contained HTML page (three.js, no network): bodies as "
                                             "ellipsoids from their inertia, joints as lines, play, seek, speed, orbit, colour");
  sub->add_option("file", a->file, "Results file (.h5) of mbsflow run, or a modes file of mbsflow modes")->required();
  sub->add_option("--mode", a->settings.mode, "A modes file: the mode played over one period (default 1, the lowest)")
      ->check(CLI::PositiveNumber);
  sub->add_option("-o,--output", a->output, "Page to write (default: FILE.html)");
  sub->add_option("--max-frames", a->settings.max_frames, "Snapshots shown at most, evenly spread (default 1000)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-mb", a->settings.max_megabytes, "Bound on the motion data in the page, MB (default 200)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--serve", a->serve, "Serve the page over HTTP instead, made afresh from the file at each load: a live run's "
                                     "page reloads itself every --interval seconds");
  sub->add_option("--host", a->host, "--serve: IPv4 address to listen on (default 127.0.0.1, this machine only)");
  sub->add_option("--port", a->port, "--serve: port (default 8000; 0: any free one, printed)")->check(CLI::Range(0, 65535));
  sub->add_option("--interval", a->interval, "--serve: seconds between reloads of a live run's page (default 3)")
      ->check(CLI::PositiveNumber);
  return [a] { return view(*a); };
}

}  // namespace mbsflow::cli
