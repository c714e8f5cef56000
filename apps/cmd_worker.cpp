// mbsflow worker --listen ENDPOINT: serves one run of a coordinator (mbsflow run --cluster).
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/cluster_file.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/stop_signals.hpp"

namespace mbsflow::cli {
namespace {

struct WorkerArgs {
  std::string listen;
  int threads = 0;
  double idle_timeout = 0.0;
  bool quiet = false;
  int protocol = cluster_protocol_version;
  std::string cluster, key;
  bool insecure = false, insecure_network = false;
  double hang_after = -1.0;
};

int worker(const WorkerArgs& a) {
  WorkerOptions o;
  o.listen = a.listen;
  o.threads = a.threads;
  o.idle_timeout_s = a.idle_timeout;
  o.protocol_version = a.protocol;
  if (!a.cluster.empty()) {
    const ClusterKeyFile f = read_cluster_keys(a.cluster);
    o.admit = f.keys;
    const std::string secret = a.key.empty() ? f.secret_key_file : a.key;
    if (secret.empty()) throw InputError(a.cluster + ": names no secret_key; give this host's with --key");
    o.keys = read_secret_key_file(secret);
  } else if (!a.key.empty()) {
    throw InputError("--key needs --cluster: the cluster file lists the keys this worker admits");
  }
  o.insecure = a.insecure_network ? Insecure::anywhere : a.insecure ? Insecure::loopback : Insecure::no;
  o.hang_after_s = a.hang_after;
  return serve_worker_command(std::move(o), a.quiet);
}

}  // namespace

int serve_worker_command(WorkerOptions o, bool quiet) {
  o.read_model = [](const std::string& text) { return read_model_text(text, "the coordinator's model"); };
  std::string name = o.listen;
  o.listening = [&](const std::string& endpoint) {
    name = endpoint;
    // The one line on stdout: scripts and `run --processes` read the endpoint from it.
    std::printf("mbsflow worker: listening on %s\n", endpoint.c_str());
    std::fflush(stdout);
  };
  if (!quiet) o.log = [&](const std::string& line) { std::fprintf(stderr, "mbsflow worker %s: %s\n", name.c_str(), line.c_str()); };
  o.stop = install_stop_handlers();
  try {
    serve_worker(o);
  } catch (const RunError& e) {
    // The coordinator says why it stopped the run; a quiet worker need not repeat it.
    if (quiet && std::string(e.what()).rfind("stopped by the coordinator", 0) == 0) return 1;
    throw RunError("worker " + name + ": " + e.what());  // its stderr may be the coordinator's
  }
  return 0;
}

Action add_worker(CLI::App& app) {
  auto a = std::make_shared<WorkerArgs>();
  CLI::App* sub = app.add_subcommand(
      "worker", "Serve one run of a coordinator (mbsflow run --cluster); exits when the run ends or the coordinator is lost");
  sub->add_option("--listen", a->listen,
                  "Control endpoint to bind, e.g. tcp://*:5560, tcp://127.0.0.1:* (any free port) or ipc:///tmp/w0; "
                  "the bound endpoint is printed on stdout")
      ->required();
  sub->add_option("--threads", a->threads, "Threads (0, the default: all cores; the cluster file may set it)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--idle-timeout", a->idle_timeout, "Give up after this many seconds without a coordinator (default: wait)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("-q,--quiet", a->quiet, "Print only errors");
  sub->add_option("--cluster", a->cluster,
                  "The cluster file: this worker admits only the coordinator and workers whose public keys it lists "
                  "(ZeroMQ CURVE), with this host's secret key from its secret_key or --key");
  sub->add_option("--key", a->key, "This host's secret key file (mbsflow keygen), if not the cluster file's secret_key");
  sub->add_flag("--insecure", a->insecure, "Serve without keys, on a loopback endpoint only: any local user could drive it")
      ->excludes(sub->get_option("--cluster"));
  sub->add_flag("--insecure-network", a->insecure_network,
                "Serve without keys on any endpoint: only where everyone who can reach the port is trusted")
      ->excludes(sub->get_option("--cluster"));
  // For tests of the version check: pretend another protocol version.
  sub->add_option("--protocol-version", a->protocol)->group("");
  // For tests of the watchdog: a step that never ends, this many seconds into the run.
  sub->add_option("--test-hang-after", a->hang_after)->group("");
  return [a] { return worker(*a); };
}

}  // namespace mbsflow::cli
