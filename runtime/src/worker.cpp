// mbsflow worker: one session with a coordinator (see cluster.hpp, docs/cluster.md).
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <cstdio>

#include "cluster_wire.hpp"
#include "mbsflow/graph/error.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "remote_exchange.hpp"
#include "schedules.hpp"
#include "step_grid.hpp"
#include "worker_io.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;
using partitioned::Part;

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

// What the coordinator told this worker to run.
struct Session {
  Model model;
  Decomposition d;
  std::vector<int> worker_of;
  int me = 0;
  RunOptions o;
  std::string results_address;
};

Session read_setup(const WorkerOptions& wo, const json& setup) {
  Session s{wo.read_model(setup.at("model").get<std::string>()), {}, {}, 0, {}, {}};
  s.d = decompose(s.model, setup.at("part_of_body").get<std::vector<int>>(), setup.at("submodels").get<int>());
  s.worker_of = setup.at("worker_of").get<std::vector<int>>();
  s.me = setup.at("worker").get<int>();
  const json& o = setup.at("options");
  s.o.method = Method::rk4;
  s.o.t_start = o.at("t_start").get<double>();
  s.o.t_end = o.at("t_end").get<double>();
  s.o.step = o.at("step").get<double>();
  s.o.output_every = o.at("output_every").get<int>();
  s.results_address = setup.at("results_address").get<std::string>();
  return s;
}

struct Outcome {
  std::string failure;               // empty when this worker's part completed
  std::optional<json> last_command;  // the coordinator's word after it: finish or abort
};

// Runs this worker's submodels; snapshots and progress go to the coordinator. Waits for
// the coordinator's finish or abort before its sockets close (linger 0): until then the
// last results and boundary values may still be on their way.
Outcome run_part(Session& s, WorkerIo& io, zmq::context_t& ctx, zmq::socket_t& inbox, const json& start, int threads,
                     const std::atomic<bool>* stop) {
  const std::size_t k = s.d.submodels.size();
  std::vector<std::unique_ptr<Part>> owned(k);
  std::vector<Part*> parts(k, nullptr);
  std::vector<int> mine;  // local submodels, ascending
  for (std::size_t q = 0; q < k; ++q)
    if (s.worker_of[q] == s.me) {
      owned[q] = std::make_unique<Part>(s.model, s.d.submodels[q], 4);
      parts[q] = owned[q].get();
      mine.push_back(static_cast<int>(q));
    }
  const ClusterTimeouts t = io.timeouts();
  RemoteExchange exchange(ctx, inbox, s.d, parts, s.worker_of, start.at("names").get<std::vector<std::string>>(),
                          start.at("data_addresses").get<std::vector<std::string>>(), 4, t.lost_s);
  io.attach(&exchange);
  zmq::socket_t results = wire::make_socket(ctx, zmq::socket_type::push);
  results.set(zmq::sockopt::sndtimeo, static_cast<int>(t.lost_s * 1000.0));
  wire::connect(results, s.results_address, "the coordinator's results inbox");
  auto report = [&](wire::ResultKind kind, long step, const void* data, std::size_t bytes) {
    wire::ResultHeader h;
    h.kind = kind;
    h.worker = s.me;
    h.step = step;
    bool ok = false;
    try {
      ok = wire::send_framed(results, h, data, bytes);
    } catch (const zmq::error_t&) {
    }
    if (!ok) exchange.abort("the coordinator stopped taking results");
  };

  const StepGrid grid = step_grid(s.o.t_start, s.o.t_end, s.o.step);
  long first = 0;
  RemoteInputs remote;
  remote.local.assign(k, 0);
  for (int q : mine) remote.local[static_cast<std::size_t>(q)] = 1;
  remote.wait = [&](int c, std::size_t q, std::size_t p, int st) {
    exchange.wait(first + c, st, static_cast<int>(q), static_cast<int>(p));
  };
  const int chunk = chunk_length(s.o.output_every);
  Scheduler schedule(
      s.d, chunk, 4,
      [&](std::size_t p, int st, int c, Half half) {
        if (exchange.aborted()) return;
        try {
          const long n = first + c;
          Part& part = *parts[p];
          if (half == Half::inner) {  // needs no ghost values: runs while they travel
            partitioned::rk4_inner_stage(part, st, grid.time(n), grid.time(n + 1));
            return;
          }
          for (const Submodel::Exchange& e : part.sub->exchanges)
            if (parts[static_cast<std::size_t>(e.neighbour)])
              partitioned::copy_ghosts(*parts[static_cast<std::size_t>(e.neighbour)], e, part, st);
          exchange.receive(static_cast<int>(p), n, st);
          partitioned::rk4_edge_stage(part, st, grid.time(n), grid.time(n + 1));
          // The values this stage made: stage input st+1, or after the last stage the next step's state.
          const long n_next = st == 3 ? n + 1 : n;
          if (n_next < grid.steps) exchange.send(static_cast<int>(p), n_next, (st + 1) % 4);
        } catch (const std::exception& e) {
          exchange.abort(e.what());
        }
      },
      false, &remote);

  std::vector<double> snapshot;
  std::string failure;
  // A proxy waits on its thread (see RemoteInputs): one thread per local submodel at least.
  tbb::task_arena arena(std::max(threads > 0 ? threads : tbb::info::default_concurrency(), static_cast<int>(mine.size())));
  arena.execute([&] {
    step_in_chunks(
        grid, chunk, 0,
        [&](long from, int steps) {
          if (!failure.empty()) return;
          first = from;
          schedule.run(steps);
        },
        [&](long done) {
          if (!failure.empty()) return;
          if (exchange.aborted()) {
            failure = exchange.why();
            return;
          }
          for (int q : mine)
            if (auto dv = find_divergence(parts[static_cast<std::size_t>(q)]->system.layout(),
                                          parts[static_cast<std::size_t>(q)]->x[0], parts[static_cast<std::size_t>(q)]->own)) {
              dv->body = parts[static_cast<std::size_t>(q)]->sub->own[static_cast<std::size_t>(dv->body)];
              failure = divergence_message(s.model, *dv, grid.time(done), s.o.method, s.o.step);
              return;
            }
          if (stop && stop->load()) {
            char buf[96];
            std::snprintf(buf, sizeof buf, "the worker was interrupted at t = %.6g s", grid.time(done));
            failure = buf;
            return;
          }
          if (done % s.o.output_every == 0 || done == grid.steps) {
            snapshot.clear();
            for (int q : mine) {
              const Part& part = *parts[static_cast<std::size_t>(q)];
              const std::size_t at = snapshot.size();
              snapshot.resize(at + static_cast<std::size_t>(part.own) * partitioned::body_numbers);
              std::vector<int> own(static_cast<std::size_t>(part.own));
              for (std::size_t i = 0; i < own.size(); ++i) own[i] = static_cast<int>(i);
              partitioned::pack_bodies(part.system.layout(), part.x[0], own, snapshot.data() + at);
            }
            report(wire::ResultKind::snapshot, done, snapshot.data(), snapshot.size() * sizeof(double));
          } else {
            report(wire::ResultKind::progress, done, nullptr, 0);
          }
        });
  });
  if (failure.empty() && exchange.aborted()) failure = exchange.why();
  const double counts[2] = {static_cast<double>(exchange.messages_sent()), exchange.bytes_per_stage()};
  if (failure.empty()) {
    report(wire::ResultKind::done, grid.steps, counts, sizeof counts);
    if (exchange.aborted()) failure = exchange.why();
  } else if (failure.rfind("stopped by the coordinator", 0) != 0 && failure.rfind("the coordinator", 0) != 0)
    report(wire::ResultKind::failed, first, failure.data(), failure.size());
  Outcome out{failure, io.next_command(io.timeouts().lost_s + 1.0)};
  io.attach(nullptr);
  return out;
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
    refuse(io, std::string("cannot set up the run: ") + e.what());
  }
  zmq::socket_t inbox = wire::make_socket(ctx, zmq::socket_type::pull);
  std::string data_address;
  try {
    const std::string bind = setup.at("data_bind").get<std::string>();
    wire::bind(inbox, bind, "the worker's inbox for boundary values");
    data_address = wire::reachable_address(inbox, setup.value("data_address", std::string()), "the worker's inbox " + bind);
  } catch (const std::exception& e) {
    refuse(io, e.what());
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
  const auto [failure, last] = run_part(s, io, ctx, inbox, start, threads, wo.stop);
  if (!failure.empty()) throw RunError(failure);
  if (last && last->value("type", "") == "finish") io.goodbye();
  if (!last || last->value("type", "") != "finish")
    throw RunError(last ? "the run ended with '" + last->value("type", std::string()) + "' from the coordinator: " +
                              last->value("reason", std::string())
                        : std::string("the coordinator did not finish the run"));
  log("run finished");
}

}  // namespace mbsflow
