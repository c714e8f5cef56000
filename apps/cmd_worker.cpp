// mbsflow worker --listen ENDPOINT: serves one run of a coordinator (mbsflow run --cluster).
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "signals.hpp"

namespace mbsflow::cli {
namespace {

struct WorkerArgs {
  std::string listen;
  int threads = 0;
  double idle_timeout = 0.0;
  bool quiet = false;
  int protocol = cluster_protocol_version;
};

int worker(const WorkerArgs& a) {
  WorkerOptions o;
  o.listen = a.listen;
  o.threads = a.threads;
  o.idle_timeout_s = a.idle_timeout;
  o.protocol_version = a.protocol;
  o.read_model = [](const std::string& text) { return read_model_text(text, "the coordinator's model"); };
  std::string name = a.listen;
  o.listening = [&](const std::string& endpoint) {
    name = endpoint;
    // The one line on stdout: scripts and `run --processes` read the endpoint from it.
    std::printf("mbsflow worker: listening on %s\n", endpoint.c_str());
    std::fflush(stdout);
  };
  if (!a.quiet) o.log = [&](const std::string& line) { std::fprintf(stderr, "mbsflow worker %s: %s\n", name.c_str(), line.c_str()); };
  o.stop = install_stop_handlers();
  try {
    serve_worker(o);
  } catch (const RunError& e) {
    // The coordinator says why it stopped the run; a quiet worker need not repeat it.
    if (a.quiet && std::string(e.what()).rfind("stopped by the coordinator", 0) == 0) return 1;
    throw RunError("worker " + name + ": " + e.what());  // its stderr may be the coordinator's
  }
  return 0;
}

}  // namespace

Action add_worker(CLI::App& app) {
  auto a = std::make_shared<WorkerArgs>();
  CLI::App* sub = app.add_subcommand(
      "worker", "Serve one run of a coordinator (mbsflow run --cluster); exits when the run ends or the coordinator is lost");
  sub->add_option("--listen", a->listen,
                  "Control endpoint to bind, e.g. tcp://*:5560, tcp://127.0.0.1:* (any free port) or ipc:///tmp/w0; "
                  "the bound endpoint is printed on stdout")
      ->required();
  sub->add_option("--threads", a->threads, "Threads (default: all cores; the cluster file may set it)")
      ->check(CLI::Range(1, 4096));
  sub->add_option("--idle-timeout", a->idle_timeout, "Give up after this many seconds without a coordinator (default: wait)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("-q,--quiet", a->quiet, "Print only errors");
  // For tests of the version check: pretend another protocol version.
  sub->add_option("--protocol-version", a->protocol)->group("");
  return [a] { return worker(*a); };
}

}  // namespace mbsflow::cli
