// mbsflow worker: one session with a coordinator (see cluster.hpp, docs/cluster.md).
#include <cstdio>

#include "cluster_wire.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "options_json.hpp"
#include "worker_part.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;

// The next command, which must be of type `want`; RunError for an abort, a lost
// coordinator, a stop request, silence beyond timeout_s (> 0) or anything else.
json expect(WorkerIo& io, const std::string& want, double timeout_s, const std::atomic<bool>* stop) {
  const auto start = wire::Clock::now();
  std::optional<json> j;
  while (!j) {
    if (stop && stop->load()) throw RunError("interrupted while waiting for the coordinator");
    if (timeout_s > 0.0 && wire::seconds_since(start) > timeout_s) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "no coordinator called within %.3g s", timeout_s);
      throw RunError(buf);
    }
    j = io.next_command(0.1);
  }
  const std::string type = j->value("type", "");
  if (type == want) return *j;
  if (type == "lost") throw RunError(j->value("reason", "the coordinator was lost"));
  if (type == "abort") throw RunError("stopped by the coordinator: " + j->value("reason", std::string()));
  throw RunError("the coordinator sent '" + type + "' where '" + want + "' was due");
}

// Tells the coordinator why this worker cannot go on, and waits (a second at most) for
// its abort, so that the message is out before the socket closes (linger 0).
[[noreturn]] void refuse(WorkerIo& io, const std::string& why) {
  io.send({{"type", "error"}, {"message", why}});
  (void)io.next_command(1.0);
  throw RunError(why);
}

Session read_setup(const WorkerOptions& wo, const json& setup) {
  Session s{wo.read_model(setup.at("model").get<std::string>()), {}, {}, 0, {}, {}, std::nullopt, 0.0};
  s.d = decompose(s.model, setup.at("part_of_body").get<std::vector<int>>(), setup.at("submodels").get<int>());
  s.worker_of = setup.at("worker_of").get<std::vector<int>>();
  s.me = setup.at("worker").get<int>();
  s.o = options_from_json(setup.at("options"));
  s.results_address = setup.at("results_address").get<std::string>();
  if (setup.contains("loose")) s.loose = loose_from_json(setup.at("loose"));
  s.exchange_delay_s = setup.value("exchange_delay_s", 0.0);
  return s;
}

}  // namespace

void serve_worker(const WorkerOptions& wo) {
  zmq::context_t ctx;
  WorkerIo io(ctx, wo.listen);
  auto log = [&](const std::string& line) {
    if (wo.log) wo.log(line);
  };
  if (wo.listening) wo.listening(io.endpoint());
  const json hello = expect(io, "hello", wo.idle_timeout_s, wo.stop);
  const std::string program = hello.value("program", "?");
  const int protocol = hello.value("protocol", -1);
  if (program != MBSFLOW_PROGRAM_VERSION || protocol != wo.protocol_version) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "version mismatch: coordinator runs mbsflow %s (protocol %d), this worker %s (protocol %d)",
                  program.c_str(), protocol, MBSFLOW_PROGRAM_VERSION, wo.protocol_version);
    refuse(io, buf);
  }
  io.send({{"type", "hello_ok"}, {"program", MBSFLOW_PROGRAM_VERSION}, {"protocol", wo.protocol_version}});
  log("coordinator " + hello.value("coordinator", std::string("?")) + " connected; this is worker " +
      hello.value("name", std::string("?")));
  // Setup: the model can be large; the coordinator's heartbeats tell it is still there.
  const json setup = expect(io, "setup", 0.0, wo.stop);
  Session s;
  try {
    s = read_setup(wo, setup);
  } catch (const std::exception& e) {
    refuse(io, "cannot set up the run: " + error_text(e));
  }
  zmq::socket_t inbox = wire::make_socket(ctx, zmq::socket_type::pull);
  std::string data_address;
  try {
    const std::string bind = setup.at("data_bind").get<std::string>();
    wire::bind(inbox, bind, "the worker's inbox for boundary values");
    data_address = wire::reachable_address(inbox, setup.value("data_address", std::string()), "the worker's inbox " + bind);
  } catch (const std::exception& e) {
    refuse(io, error_text(e));
  }
  io.send({{"type", "ready"}, {"data_address", data_address}});
  const json start = expect(io, "start", 0.0, wo.stop);
  int own = 0;
  std::string list;
  for (std::size_t q = 0; q < s.worker_of.size(); ++q)
    if (s.worker_of[q] == s.me) {
      own += static_cast<int>(s.d.submodels[q].own.size());
      list += (list.empty() ? "" : ",") + std::to_string(q);
    }
  log("running submodels " + list + " of " + std::to_string(s.worker_of.size()) + " (" + std::to_string(own) +
      " bodies), inbox " + data_address);
  const int threads = setup.value("threads", 0) > 0 ? setup.value("threads", 0) : wo.threads;
  const Outcome outcome = (s.loose ? run_loose_part : run_tight)(s, io, ctx, inbox, start, threads, wo.stop);
  const auto& [failure, last] = outcome;
  if (!failure.empty()) throw RunError(failure);
  if (last && last->value("type", "") == "finish") io.goodbye();
  if (!last || last->value("type", "") != "finish")
    throw RunError(last ? "the run ended with '" + last->value("type", std::string()) + "' from the coordinator: " +
                              last->value("reason", std::string())
                        : std::string("the coordinator did not finish the run"));
  log("run finished");
}

}  // namespace mbsflow
