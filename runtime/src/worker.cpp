// mbsflow worker: one session with a coordinator (see cluster.hpp, docs/cluster.md).
#include <algorithm>
#include <cstdio>

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "options_json.hpp"
#include "worker_io.hpp"
#include "worker_part.hpp"
#include "zap_guard.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;

// The next command, which must be of type `want`; RunError for an abort, a lost
// coordinator, a stop request, silence beyond timeout_s (> 0; the clock stops once
// `begun` is set: a set-up whose model is on its way) or anything else.
json expect(WorkerIo& io, const std::string& want, double timeout_s, const std::atomic<bool>* stop,
            const std::atomic<bool>* begun = nullptr) {
  const auto start = wire::Clock::now();
  std::optional<json> j;
  while (!j) {
    if (stop && stop->load()) throw RunError("interrupted while waiting for the coordinator");
    if (timeout_s > 0.0 && !(begun && begun->load()) && wire::seconds_since(start) > timeout_s) {
      char buf[96];
      if (want == "hello")
        std::snprintf(buf, sizeof buf, "no coordinator called within %.3g s", timeout_s);
      else
        std::snprintf(buf, sizeof buf, "the coordinator sent no %s within %.3g s", want.c_str(), timeout_s);
      throw RunError(buf);
    }
    j = io.next_command(0.1);
  }
  const std::string type = wire::text(*j, "type");
  if (type == want) return *j;
  if (type == "lost") throw RunError(wire::text(*j, "reason", "the coordinator was lost"));
  if (type == "abort") throw RunError("stopped by the coordinator: " + wire::text(*j, "reason"));
  throw RunError("the coordinator sent '" + type + "' where '" + want + "' was due");
}

// Tells the coordinator why this worker cannot go on, and waits (a second at most) for
// its abort, so that the message is out before the socket closes (linger 0).
[[noreturn]] void refuse(WorkerIo& io, const std::string& why) {
  io.send({{"type", "error"}, {"message", why}});
  (void)io.next_command(1.0);
  throw RunError(why);
}

// An integer of a set-up message in [lo, hi]; RunError otherwise (nothing converted
// before it is known to fit).
int setup_integer(const json& v, const char* what, int lo, int hi) {
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
    throw RunError(std::string("the set-up's ") + what + " is not an integer in [" + std::to_string(lo) + ", " +
                   std::to_string(hi) + "]");
  return static_cast<int>(v.get<long long>());
}

std::vector<int> setup_integers(const json& v, const char* what, int lo, int hi) {
  if (v.is_string()) {  // a long list comes as text (wire::integer_list_text)
    std::optional<std::vector<int>> out = wire::integer_list(v.get_ref<const std::string&>(), lo, hi);
    if (!out)
      throw RunError(std::string("the set-up's ") + what + " is not a list of integers in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
    return std::move(*out);
  }
  if (!v.is_array()) throw RunError(std::string("the set-up's ") + what + " is not a list");
  std::vector<int> out;
  out.reserve(v.size());
  for (const json& x : v) out.push_back(setup_integer(x, what, lo, hi));
  return out;
}

// A set-up endpoint must use the transport of this worker's --listen endpoint and, for
// an ipc bind, lie in its directory: a coordinator cannot make a worker bind over any
// file (ZeroMQ removes what is at an ipc path it binds).
void check_endpoint(const std::string& e, const std::string& listen, const char* what, bool bind = false) {
  const auto scheme = [](const std::string& x) { return x.substr(0, x.find("://")); };
  if (scheme(e) != scheme(listen) || e.find("://") == std::string::npos)
    throw RunError(std::string("the set-up's ") + what + " " + e + " is not a " + scheme(listen) + " endpoint like --listen");
  if (bind && scheme(e) == "ipc") {
    const auto dir = [](const std::string& x) { return x.substr(0, x.rfind('/') + 1); };
    if (dir(e) != dir(listen) || e.find("..") != std::string::npos)
      throw RunError(std::string("the set-up's ") + what + " " + e + " is not in the directory of --listen " + listen);
  }
}

// The start message: a name and a data address (checked like the set-up's) per worker.
void check_start(const json& start, const Session& s, const std::string& listen) {
  const std::size_t workers = s.workers();
  for (const char* key : {"names", "data_addresses"}) {
    const auto it = start.find(key);
    if (it == start.end() || !it->is_array() || it->size() != workers)
      throw RunError(std::string("the start's ") + key + " is not a list of " + std::to_string(workers) + " strings");
    for (const json& v : *it) {
      if (!v.is_string()) throw RunError(std::string("the start's ") + key + " is not a list of strings");
      if (key == std::string("data_addresses")) check_endpoint(v.get<std::string>(), listen, "data address");
    }
  }
}

Session read_setup(const WorkerOptions& wo, const json& setup, const std::string& listen) {
  Session s;
  s.model = wo.read_model(setup.at("model").get_ref<const std::string&>());
  const int bodies = static_cast<int>(s.model.bodies.size());
  const int k = setup_integer(setup.at("submodels"), "submodels", 1, std::max(1, bodies));
  s.d = decompose(s.model, setup_integers(setup.at("part_of_body"), "part_of_body", 0, k - 1), k);
  s.worker_of = setup_integers(setup.at("worker_of"), "worker_of", 0, k - 1);
  if (s.worker_of.size() != static_cast<std::size_t>(k)) throw RunError("the set-up's worker_of does not name a worker per submodel");
  s.me = setup_integer(setup.at("worker"), "worker", 0, k - 1);
  s.o = options_from_json(setup.at("options"));
  s.results_address = setup.at("results_address").get<std::string>();
  check_endpoint(s.results_address, listen, "results address");
  check_endpoint(setup.at("data_bind").get<std::string>(), listen, "data_bind", true);
  if (setup.contains("loose")) s.loose = loose_from_json(setup.at("loose"));
  s.exchange_delay_s = wire::number(setup, "exchange_delay_s", 0.0, 60.0).value_or(0.0);
  s.threads = setup.contains("threads") ? setup_integer(setup.at("threads"), "threads", 0, 65536) : 0;
  if (setup.contains("resume")) {
    const auto bytes = setup.at("resume").is_string() ? wire::unhex(setup.at("resume").get<std::string>()) : std::nullopt;
    if (!bytes || bytes->empty()) throw RunError("the set-up's resume is not a state in hex digits");
    s.resume = std::move(*bytes);
  }
  return s;
}

// The worker's CURVE settings, or null for an insecure worker (InputError unless asked for,
// and on loopback unless asked for anywhere).
std::optional<wire::Security> worker_security(const WorkerOptions& wo) {
  if (wo.keys) {
    if (!is_curve_key(wo.admit.coordinator)) throw InputError("the cluster file gives no public_key of the coordinator");
    return wire::Security{*wo.keys, wo.admit.coordinator, {}};
  }
  if (wo.insecure == Insecure::no)
    throw InputError("no key: give the cluster file and this host's secret key (mbsflow keygen), or --insecure to "
                     "serve any coordinator on this host");
  if (wo.insecure == Insecure::loopback && !wire::loopback(wo.listen))
    throw InputError("--insecure serves this host only, and " + wo.listen +
                     " is not a loopback endpoint: give keys, or --insecure-network");
  return std::nullopt;
}

}  // namespace

void serve_worker(const WorkerOptions& wo) {
  const std::optional<wire::Security> security = worker_security(wo);
  zmq::context_t ctx;
  auto log = [&](const std::string& line) {
    if (wo.log) wo.log(line);
  };
  std::optional<ZapGuard> zap;  // before the sockets: it outlives them
  if (security) {
    zap.emplace(ctx, [&](const std::string& line) { log(line); });
    zap->allow("control", wo.admit.coordinator);
    for (const std::string& k : wo.admit.workers) zap->allow("data", k);
  }
  WorkerIo io(ctx, wo.listen, security ? &*security : nullptr);
  if (wo.listening) wo.listening(io.endpoint());
  const json hello = expect(io, "hello", wo.idle_timeout_s, wo.stop);
  const std::string program = wire::text(hello, "program", "?");
  const int protocol = static_cast<int>(wire::number(hello, "protocol", -1e9, 1e9).value_or(-1));
  if (program != MBSFLOW_PROGRAM_VERSION || protocol != wo.protocol_version) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "version mismatch: coordinator runs mbsflow %s (protocol %d), this worker %s (protocol %d)",
                  program.c_str(), protocol, MBSFLOW_PROGRAM_VERSION, wo.protocol_version);
    refuse(io, buf);
  }
  io.send({{"type", "hello_ok"}, {"program", MBSFLOW_PROGRAM_VERSION}, {"protocol", wo.protocol_version}});
  log("coordinator " + wire::text(hello, "coordinator", "?") + " connected; this is worker " +
      wire::text(hello, "name", "?"));
  // Setup: the model can be large; the coordinator's heartbeats tell it is still there. It
  // must begin within connect_s + lost_s of the hello: a peer that says hello and nothing
  // more (an --insecure worker's first caller) does not hold the worker.
  const ClusterTimeouts asked = io.timeouts();
  const json setup = expect(io, "setup", asked.connect_s + asked.lost_s, wo.stop, io.setup_begun());
  Session s;
  try {
    s = read_setup(wo, setup, io.endpoint());
    s.run = std::stoull(wire::text(hello, "run"), nullptr, 16);  // WorkerIo took only a valid one
    s.hang_after_s = wo.hang_after_s;
    if (!s.loose) prepare_tight(s);
    if (security) {
      s.security = security;
      const auto keys = setup.find("worker_keys");
      if (keys == setup.end() || !keys->is_array() || keys->size() != s.workers())
        throw RunError("the set-up gives no public key per worker");
      for (const json& k : *keys) {
        if (!k.is_string() || std::find(wo.admit.workers.begin(), wo.admit.workers.end(), k.get<std::string>()) == wo.admit.workers.end())
          throw RunError("the set-up names a worker key that this worker's cluster file does not list");
        s.security->workers.push_back(k.get<std::string>());
      }
    }
  } catch (const std::exception& e) {
    refuse(io, "cannot set up the run: " + error_text(e));
  }
  zmq::socket_t inbox = wire::make_socket(ctx, zmq::socket_type::pull, wire::max_data_bytes(s.d.layout()));
  wire::curve_server(inbox, s.security ? &*s.security : nullptr, "data");
  std::string data_address;
  try {
    const std::string bind = setup.at("data_bind").get<std::string>();
    wire::bind(inbox, bind, "the worker's inbox for boundary values");
    data_address = wire::reachable_address(inbox, wire::text(setup, "data_address"), "the worker's inbox " + bind);
  } catch (const std::exception& e) {
    refuse(io, error_text(e));
  }
  io.send({{"type", "ready"}, {"data_address", data_address}});
  const json start = expect(io, "start", 0.0, wo.stop);
  try {
    check_start(start, s, io.endpoint());
  } catch (const std::exception& e) {
    refuse(io, "cannot start the run: " + error_text(e));
  }
  int own = 0;
  std::string list;
  for (std::size_t q = 0; q < s.worker_of.size(); ++q)
    if (s.worker_of[q] == s.me) {
      own += static_cast<int>(s.d.submodels[q].own.size());
      list += (list.empty() ? "" : ",") + std::to_string(q);
    }
  log("running submodels " + list + " of " + std::to_string(s.worker_of.size()) + " (" + std::to_string(own) +
      " bodies), inbox " + data_address);
  const int threads = s.threads > 0 ? s.threads : wo.threads;
  const std::unique_ptr<WorkerTransport> transport = zmq_worker_transport(ctx, inbox, io);
  const Outcome outcome = (s.loose ? run_loose_part : run_tight)(s, *transport, start, threads, wo.stop);
  const auto& [failure, last] = outcome;
  if (!failure.empty()) throw RunError(failure);
  if (last && wire::text(*last, "type") == "finish") io.goodbye();
  if (!last || wire::text(*last, "type") != "finish")
    throw RunError(last ? "the run ended with '" + wire::text(*last, "type") + "' from the coordinator: " +
                              wire::text(*last, "reason")
                        : std::string("the coordinator did not finish the run"));
  log("run finished");
}

}  // namespace mbsflow
