// mbsflow run --cluster / --processes: the coordinator (see cluster.hpp, docs/cluster.md).
#include <chrono>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <optional>

#include "coordinator_transport.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "coupling_log.hpp"
#include "options_json.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "partitioned_state.hpp"
#include "sink_runner.hpp"
#include "mbsflow/methods/step_grid.hpp"
#include "random_id.hpp"
#include "tight_coupling.hpp"

namespace mbsflow {
namespace {

using nlohmann::json;
using wire::Clock;

bool known_kind(wire::ResultKind k) {
  const auto v = static_cast<std::uint32_t>(k);
  return v >= static_cast<std::uint32_t>(wire::ResultKind::snapshot) && v <= static_cast<std::uint32_t>(wire::ResultKind::checkpoint);
}

struct Peer {
  const ClusterWorker* config;
  Clock::time_point heard;
  std::string data_address;
  partitioned::StateShare share;  // its own bodies and modes, in the order it sends them
  std::string submodels;    // "0,1": for messages
  double stalled_s = 0.0;   // its computation's last report of how long it has not advanced
  long completed = 0;       // steps it has reported done
  double reached = 0.0;     // the model time it has reported
  bool answered = false, done = false;
};

class Coordinator {
 public:
  Coordinator(const ClusterConfig& c, const RunOptions& o, const StateLayout& state) : c_(c), o_(o) {
    if (c.keys) {
      security_ = wire::Security{*c.keys, c.coordinator_key, {}};
      for (const ClusterWorker& w : c.workers) security_->workers.push_back(w.public_key);
    }
    net_ = make_zmq_coordinator_transport(c, state, security(), run_);
    for (const ClusterWorker& w : c.workers) peers_.push_back({&w, Clock::now(), {}, {}, {}, 0.0, 0, o.t_start, false, false});
  }

  std::string who(std::size_t w) const {
    const Peer& p = peers_[w];
    return "worker " + p.config->name + " (" + p.config->address + (p.submodels.empty() ? "" : ", submodels " + p.submodels) + ")";
  }

  void send(std::size_t w, json j) {
    // A full queue means the worker has not taken anything for a long time; the heartbeat
    // check reports it.
    j["run"] = id_text(run_);
    (void)net_->send(w, j);
  }
  // The set-up's model after the set-up message, as "model_part" messages of a header and
  // up to wire::model_part_bytes of text, heartbeats going out between them. The parts
  // refer to the text without copying it: it belongs to run_cluster's caller and outlives
  // this object, whose context ends (waiting for its I/O thread) before run_cluster returns.
  void send_model(std::size_t w, std::string_view text) {
    const json head = {{"type", "model_part"}, {"run", id_text(run_)}};
    for (std::size_t at = 0; at < text.size(); at += wire::model_part_bytes) {
      const std::size_t n = std::min(wire::model_part_bytes, text.size() - at);
      if (!net_->send_with(w, head, text.substr(at, n)))
        return;  // the worker has taken nothing for long: the heartbeat check reports it
      beat_if_due();
    }
  }
  // Heartbeats when due, between long steps outside pump (the set-ups of a large model).
  void beat_if_due() {
    if (wire::seconds_since(beat_) < c_.timeouts.heartbeat_s) return;
    beat_ = Clock::now();
    send_all({{"type", "heartbeat"}});
  }
  const wire::Security* security() const { return security_ ? &*security_ : nullptr; }
  void send_all(const json& j) {
    for (std::size_t w = 0; w < peers_.size(); ++w) send(w, j);
  }

  // RunError with a worker's error reply.
  void throw_if_error(std::size_t w, const json& j) const {
    if (wire::text(j, "type") == "error") throw RunError(who(w) + ": " + wire::text(j, "message", "failed"));
  }

  // Waits until every worker has answered with `want`, sending heartbeats; RunError on an error reply, a lost worker or, with a deadline, silence.
  void gather(const std::string& want, double deadline_s, const std::function<void(std::size_t, const json&)>& take) {
    for (Peer& p : peers_) p.answered = false;
    const auto start = Clock::now();
    while (std::any_of(peers_.begin(), peers_.end(), [](const Peer& p) { return !p.answered; })) {
      pump(
          [&](std::size_t w, const json& j) {
            const std::string type = wire::text(j, "type");
            if (type == want) {
              peers_[w].answered = true;
              take(w, j);
            } else {
              throw_if_error(w, j);
            }
          },
          nullptr);
      if (deadline_s > 0.0 && wire::seconds_since(start) > deadline_s)
        for (std::size_t w = 0; w < peers_.size(); ++w)
          if (!peers_[w].answered) {
            char buf[96];
            std::snprintf(buf, sizeof buf, " did not answer within %.3g s", deadline_s);
            throw RunError(who(w) + buf + "; is `mbsflow worker --listen` running there, and reachable from here?");
          }
      if (deadline_s <= 0.0) check_alive("");
      check_stop(o_, o_.t_start);  // Ctrl-C during the set-up
    }
  }

  // One round of waiting while the workers wait for the start: heartbeats, a worker's
  // error, a lost worker, Ctrl-C.
  void wait_for_start() {
    pump(
        [&](std::size_t w, const json& j) { throw_if_error(w, j); }, nullptr, 0.0);
    check_alive("");
    check_stop(o_, o_.t_start);
  }

  // One round of waiting (at most a heartbeat interval, or max_wait_s): control messages
  // to on_control, results to on_result; sends heartbeats when due.
  void pump(const std::function<void(std::size_t, const json&)>& on_control,
            const std::function<void(const wire::ResultHeader&, std::string_view)>& on_result,
            double max_wait_s = std::numeric_limits<double>::infinity()) {
    const double wait = std::min(max_wait_s, std::max(0.0, c_.timeouts.heartbeat_s - wire::seconds_since(beat_)) + 0.001);
    net_->poll(
        wait,
        [&](std::size_t w, const json& j) {
          // A worker's error before it knew the run (a refused hello) carries no run id.
          if (wire::text(j, "run") != id_text(run_) && wire::text(j, "type") != "error") return;
          peers_[w].heard = Clock::now();
          if (wire::text(j, "type") == "heartbeat")
            peers_[w].stalled_s = wire::number(j, "stalled_s", 0.0, 1e12).value_or(0.0);
          else
            on_control(w, j);
        },
        [&](const wire::ResultHeader& h, std::string_view payload) {
          // A result of this run from one of its workers only: a stray or forged frame can
          // neither end nor stop the run.
          if (h.worker < 0 || h.worker >= static_cast<int>(peers_.size()) || !known_kind(h.kind)) return;
          peers_[static_cast<std::size_t>(h.worker)].heard = Clock::now();
          if (on_result) on_result(h, payload);
        });
    beat_if_due();
  }

  // RunError naming a worker that is silent (killed, stopped, cut off) or whose
  // computation has not advanced for stall_s while it still answers (a hung step).
  void check_alive(const std::string& progress) {
    for (std::size_t w = 0; w < peers_.size(); ++w) {
      char buf[160];
      if (wire::seconds_since(peers_[w].heard) > c_.timeouts.lost_s) {
        std::snprintf(buf, sizeof buf, " was lost: nothing heard from it for %.1f s", c_.timeouts.lost_s);
        throw RunError(who(w) + buf + progress);
      }
      if (peers_[w].stalled_s > c_.timeouts.stall_s) {
        std::snprintf(buf, sizeof buf, " is hung: its computation has not advanced for %.1f s (timeouts.stall_s %.3g)",
                      peers_[w].stalled_s, c_.timeouts.stall_s);
        throw RunError(who(w) + buf + progress);
      }
    }
  }

  // Ends the run and waits (lost_s at most) for every worker's goodbye, so that no socket
  // closes (linger 0) before the finish has reached its worker.
  void finish() {
    send_all({{"type", "finish"}});
    std::size_t left = peers_.size();
    const auto start = Clock::now();
    while (left > 0 && wire::seconds_since(start) < c_.timeouts.lost_s)
      pump([&](std::size_t, const json& j) { left -= wire::text(j, "type") == "bye"; }, nullptr);
  }
  // Stops every worker. The sockets of the workers still heard from then close with a
  // linger of one second instead of none: bounded, and long enough for the abort to go
  // out; a lost worker's socket closes at once.
  void abort(const std::string& reason) {
    send_all({{"type", "abort"}, {"reason", reason}});
    for (std::size_t w = 0; w < peers_.size(); ++w)
      if (wire::seconds_since(peers_[w].heard) < c_.timeouts.lost_s) net_->linger(w, 1.0);
  }

  std::vector<Peer>& peers() { return peers_; }
  const std::string& results_address() const { return net_->results_address(); }

 private:
  const ClusterConfig& c_;
  const RunOptions& o_;
  std::uint64_t run_ = random_id();
  std::optional<wire::Security> security_;
  std::unique_ptr<CoordinatorTransport> net_;
  std::vector<Peer> peers_;
  Clock::time_point beat_ = Clock::now();
};

json setup_message(std::size_t model_bytes, const Decomposition& d, const std::vector<int>& worker_of, std::size_t w,
                   const ClusterWorker& cw, const RunOptions& o, const std::string& results_address,
                   const ClusterCoupling& coupling, const wire::Security* security, const std::string& resume) {
  // The model's text follows in parts (Coordinator::send_model).
  json j = {{"type", "setup"},
          {"model_bytes", model_bytes},
          {"part_of_body", wire::integer_list_text(d.part_of_body)},  // text: a list of a million values would cost 25 bytes a byte
          {"submodels", d.submodels.size()},
          {"worker_of", worker_of},
          {"worker", w},
          {"options", options_to_json(o)},
          {"data_bind", cw.data_bind},
          {"data_address", cw.data_address},
          {"results_address", results_address},
          {"threads", cw.threads},
          {"exchange_delay_s", coupling.exchange_delay_s}};
  if (coupling.loose) j["loose"] = loose_to_json(*coupling.loose);
  if (security) j["worker_keys"] = security->workers;  // the peers' inboxes' server keys
  if (!resume.empty()) j["resume"] = resume;             // hex: the state to go on from
  return j;
}

// Checkpoints of a run on workers (docs/cluster.md). Every worker's loop
// has the same checkpoint opportunities, numbered alike; the coordinator asks for one a
// little ahead of where they are, each worker sends its state when it gets there (or says
// that it is past it: then a later one is asked for), and once every worker's state of
// that opportunity is in, so are the snapshots before it, and none after: the results
// file is synced and the checkpoint written. Tight coupling: in the format of a run on
// threads (the point and the global state), so that it goes on with workers or threads.
// Loose coupling ("loose cluster"): the time, the submodels' workers, the coupling
// records so far and each worker's state as it sent it (its position and submodels), to
// go on with the same workers.
class ClusterCheckpoints {
 public:
  // loose: the run's merged coupling records (null: tight coupling).
  ClusterCheckpoints(const RunOptions& o, std::size_t workers, const std::vector<int>& worker_of,
                     const loose::CouplingLog* loose)
      : o_(o), timer_(o.checkpoint), states_(workers), worker_of_(worker_of), loose_(loose) {}

  // Asks for a checkpoint when one is due and none is under way.
  void poll(Coordinator& co) {
    if (at_ < 0 && timer_.due()) ask(co, seen_ + 2);
  }
  // A checkpoint result of worker w; writes the checkpoint when it completes one.
  void take(Coordinator& co, std::size_t w, const wire::ResultHeader& h, std::string_view payload,
            ResultSink* sink, const RunSummary& out, const MultibodySystem& whole) {
    seen_ = std::max(seen_, static_cast<long>(h.index));
    if (h.step != at_) return;  // an answer to an earlier request
    if (payload.size() == 0) return ask(co, seen_ + 2);  // the worker was past it
    if (states_[w].empty()) ++got_;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(payload.data());
    states_[w].assign(bytes, bytes + payload.size());
    if (got_ < states_.size()) return;
    if (loose_) return write_loose(co, sink, out);
    StateWriter out_state = checkpoint_head("tight", o_.method, sink, out);
    Eigen::VectorXd y = whole.initial_state(), own;
    std::optional<TightPoint> point;
    for (std::size_t v = 0; v < states_.size(); ++v) {
      StateReader in(states_[v], co.who(v) + "'s checkpoint");
      const partitioned::StateShare& share = co.peers()[v].share;
      TightPoint p = read_tight_point(in, static_cast<Eigen::Index>(share.numbers()), own);
      if (point && (p.steps != point->steps || p.t != point->t))
        throw RunError(co.who(v) + " sent the state of another step for a checkpoint");
      partitioned::unpack_share(whole.layout(), y, share, own.data());
      if (!point) point = std::move(p);
    }
    save_tight_point(out_state, *point, y);
    o_.checkpoint->write(out_state.take());
    at_ = -1;
  }

 private:
  void write_loose(Coordinator& co, ResultSink* sink, const RunSummary& out) {
    StateWriter w = checkpoint_head("loose cluster", o_.method, sink, out);
    double t = 0.0;
    for (std::size_t v = 0; v < states_.size(); ++v) {
      StateReader in(states_[v], co.who(v) + "'s checkpoint");
      const double tv = in.real();
      if (v > 0 && tv != t) throw RunError(co.who(v) + " sent the state of another macro step for a checkpoint");
      t = tv;
    }
    w.real(t);
    w.integer(static_cast<std::int64_t>(worker_of_.size()));
    for (int v : worker_of_) w.integer(v);
    loose_->save(w);
    w.integer(static_cast<std::int64_t>(states_.size()));
    for (const auto& s : states_) w.bytes(s);
    o_.checkpoint->write(w.take());
    at_ = -1;
  }

  void ask(Coordinator& co, long at) {
    at_ = at;
    got_ = 0;
    for (auto& s : states_) s.clear();
    co.send_all({{"type", "checkpoint"}, {"at", at}});
  }
  const RunOptions& o_;
  CheckpointTimer timer_;
  long at_ = -1, seen_ = 0;  // the opportunity asked for (-1: none); the latest a worker said it was at
  std::size_t got_ = 0;
  std::vector<std::vector<std::uint8_t>> states_;
  const std::vector<int>& worker_of_;
  const loose::CouplingLog* loose_;
};

// A checkpoint of a run on workers to go on from: out gets how far the results go, and
// the returned states are what each worker gets in its set-up (hex); `results` the
// results file's id.
std::vector<std::string> resume_states(StateReader& in, const RunOptions& o, const MultibodySystem& whole,
                                       const std::vector<int>& worker_of, std::size_t workers,
                                       loose::CouplingLog* loose, Eigen::VectorXd& y, RunSummary& out, std::string& results) {
  if (!loose) {
    results = read_checkpoint_head(in, "tight", o.method, out);
    const TightPoint point = read_tight_point(in, whole.dimension(), y);
    out.resumed_at = point.t;
    StateWriter w;
    save_tight_point(w, point, y);
    return std::vector<std::string>(workers, wire::hex(w.take()));
  }
  results = read_checkpoint_head(in, "loose cluster", o.method, out);
  out.resumed_at = in.real();
  std::vector<int> was(static_cast<std::size_t>(in.integer(0, INT32_MAX)));
  for (int& v : was) v = static_cast<int>(in.integer(0, INT32_MAX));
  if (was != worker_of) in.fail("it is of a loosely coupled run with other submodels or workers; resume it with the same ones");
  loose->restore(in);
  if (in.integer(0, INT32_MAX) != static_cast<std::int64_t>(workers)) in.fail("it is of a run on another number of workers");
  std::vector<std::string> states;
  for (std::size_t v = 0; v < workers; ++v) states.push_back(wire::hex(in.bytes()));
  return states;
}

}  // namespace

void check_cluster_run(const Model& model, const RunOptions& o, const ClusterCoupling& coupling) {
  check_options(o);
  if (coupling.loose) check_loose_options(*coupling.loose);
  if (!coupling.loose) tight_stages(o.method);  // a method whose stages the workers exchange
  if (!model.force_elements.empty())
    throw InputError("the model has " + std::to_string(model.force_elements.size()) +
                     " force elements of this program, which worker processes do not have; run it in this process "
                     "(threads, tight or loose coupling)");
}

RunSummary run_cluster(const Model& model, const std::string& model_json, const Decomposition& d,
                       const ClusterConfig& cluster, const RunOptions& o, ResultSink* sink, ClusterStats* stats,
                       ClusterCoupling coupling) {
  return run_cluster(std::make_shared<const Model>(model), model_json, d, cluster, o, sink, stats, coupling);
}

RunSummary run_cluster(std::shared_ptr<const Model> shared, const std::string& model_json, const Decomposition& d,
                       const ClusterConfig& cluster, const RunOptions& o, ResultSink* sink, ClusterStats* stats,
                       ClusterCoupling coupling) {
  const Model& model = *shared;
  check_cluster_run(model, o, coupling);
  check_cluster_security(cluster);
  if (coupling.loose) check_loose_options(*coupling.loose, d.submodels.size());
  const std::vector<int> worker_of = assign_submodels(cluster, static_cast<int>(d.submodels.size()));
  Coordinator co(cluster, o, d.layout());
  auto& peers = co.peers();
  for (std::size_t q = 0; q < d.submodels.size(); ++q) {
    Peer& p = peers[static_cast<std::size_t>(worker_of[q])];
    p.share.add(d, d.submodels[q]);
    p.submodels += (p.submodels.empty() ? "" : ",") + std::to_string(q);
  }
  RunSummary out;
  MultibodySystem whole(std::move(shared), static_cast<int>(model.bodies.size()));  // for the sink: layout, energies, joint forces
  auto start_clock = Clock::now();
  Eigen::VectorXd y = whole.initial_state();
  long evaluations = 0, steps = 0, rejected = 0;  // as the workers count them
  loose::CouplingLog coupling_log;  // loose coupling: the workers' records, merged
  // Going on from a checkpoint: the workers get its point and global state; the results
  // file is reopened once they are in.
  const Checkpointing* c = o.checkpoint;
  std::optional<StateReader> resumed;
  std::vector<std::string> resume_hex(peers.size());
  std::string results_id;
  loose::CouplingLog* log = coupling.loose ? &coupling_log : nullptr;
  if (c && !c->resume.empty()) {
    resumed.emplace(c->resume, c->resume_from);
    resume_hex = resume_states(*resumed, o, whole, worker_of, peers.size(), log, y, out, results_id);
  }
  ClusterCheckpoints checkpoints(o, peers.size(), worker_of, log);
  run_with_sink(sink, out, [&] {
    try {
      for (std::size_t w = 0; w < peers.size(); ++w)
        co.send(w, {{"type", "hello"},
                    {"program", MBSFLOW_PROGRAM_VERSION},
                    {"protocol", cluster_protocol_version},
                    {"coordinator", cluster.coordinator_name},
                    {"name", cluster.workers[w].name},
                    {"timeouts",
                     {{"connect_s", cluster.timeouts.connect_s},
                      {"heartbeat_s", cluster.timeouts.heartbeat_s},
                      {"lost_s", cluster.timeouts.lost_s}}}});
      co.gather("hello_ok", cluster.timeouts.connect_s, [](std::size_t, const json&) {});
      for (std::size_t w = 0; w < peers.size(); ++w) {
        co.send(w, setup_message(model_json.size(), d, worker_of, w, cluster.workers[w], o, co.results_address(), coupling,
                                 co.security(), resume_hex[w]));
        co.send_model(w, model_json);
      }
      co.gather("ready", 0.0, [&](std::size_t w, const json& j) { peers[w].data_address = wire::text(j, "data_address"); });
      json names = json::array(), addresses = json::array();
      for (const Peer& p : peers) {
        names.push_back(p.config->name);
        addresses.push_back(p.data_address);
      }
      // The results file only once every worker is in: a refused run writes nothing. Its
      // start (the model's text, the first snapshot) takes seconds for a million bodies,
      // so it is written on a thread of its own while this one keeps the heartbeats going.
      if (resumed || sink) {
        auto begun = std::async(std::launch::async, [&] {
          if (resumed) {
            resume_results(*resumed, *c, sink, whole, results_id, out);
          } else {
            sink->begin(whole);
            emit(whole, sink, o.t_start, y, out);
          }
        });
        while (begun.wait_for(std::chrono::milliseconds(10)) != std::future_status::ready) co.wait_for_start();
        begun.get();
      }
      co.send_all({{"type", "start"}, {"names", names}, {"data_addresses", addresses}});
      // Like run_partitioned's, the run's clock starts when the parts are set up.
      if (stats) stats->setup_seconds = std::chrono::duration<double>(Clock::now() - start_clock).count();
      start_clock = Clock::now();

      struct Pending {
        Eigen::VectorXd y;
        std::size_t parts = 0;
      };
      std::map<long, Pending> pending;  // snapshots still missing some workers' bodies
      double reached = o.t_start;       // the model time every worker has reached
      const StateLayout& layout = whole.layout();
      auto on_result = [&](const wire::ResultHeader& h, std::string_view payload) {
        const auto w = static_cast<std::size_t>(h.worker);
        Peer& p = peers[w];
        switch (h.kind) {
          case wire::ResultKind::failed:
            throw RunError(co.who(w) + ": " + std::string(payload));
          case wire::ResultKind::done: {
            if (payload.size() != wire::done_counts * sizeof(double))
              throw RunError(co.who(w) + " sent counts of the wrong size");
            p.done = true;
            double counts[wire::done_counts];
            std::memcpy(counts, payload.data(), sizeof counts);
            // Loose: each worker counts its submodels' evaluations; tight: every worker
            // counts the whole model's steps, as one process does.
            evaluations = coupling.loose ? evaluations + static_cast<long>(counts[2]) : static_cast<long>(counts[2]);
            steps = static_cast<long>(counts[3]);
            rejected = static_cast<long>(counts[4]);
            if (stats) {
              stats->messages += static_cast<long>(counts[0]);
              stats->bytes_per_stage += counts[1];
            }
            break;
          }
          case wire::ResultKind::snapshot:
          case wire::ResultKind::dense: {
            if (payload.size() != p.share.numbers() * sizeof(double))
              throw RunError(co.who(w) + " sent a snapshot of the wrong size");
            Pending& s = pending[h.index];
            if (s.y.size() == 0) s.y = y;
            partitioned::unpack_share(layout, s.y, p.share, payload.data());
            if (++s.parts == peers.size()) {
              y = std::move(s.y);
              pending.erase(h.index);
              if (h.kind == wire::ResultKind::dense) whole.after_step(h.t, y);
              if (sink) emit(whole, sink, h.t, y, out);
            }
            break;
          }
          case wire::ResultKind::progress:
            break;
          case wire::ResultKind::checkpoint:
            checkpoints.take(co, w, h, payload, sink, out, whole);
            break;
          case wire::ResultKind::coupling: {
            constexpr std::size_t row = wire::coupling_row * sizeof(double);
            if (payload.size() % row != 0) throw RunError(co.who(w) + " sent coupling records of the wrong size");
            std::vector<double> v(payload.size() / sizeof(double));
            std::memcpy(v.data(), payload.data(), payload.size());
            for (std::size_t i = 0; i < v.size(); i += wire::coupling_row)
              coupling_log.add({static_cast<long>(v[i]), v[i + 1], v[i + 2], v[i + 3], v[i + 4], static_cast<int>(v[i + 5])});
            break;
          }
        }
        p.completed = std::max(p.completed, static_cast<long>(h.step));
        p.reached = std::max(p.reached, h.t);
      };
      char where[96] = "";
      while (std::any_of(peers.begin(), peers.end(), [](const Peer& p) { return !p.done; })) {
        co.pump(
            [&](std::size_t w, const json& j) {
              if (wire::text(j, "type") == "error") throw RunError(co.who(w) + ": " + wire::text(j, "message"));
            },
            on_result);
        long all = peers.front().completed;
        double t_all = peers.front().reached;
        for (const Peer& p : peers) {
          all = std::min(all, p.completed);
          t_all = std::min(t_all, p.reached);
        }
        if (t_all > reached) {
          reached = t_all;
          std::snprintf(where, sizeof where, "; every worker had completed t = %.6g s", t_all);
          if (o.progress) o.progress(t_all, all);
        }
        co.check_alive(where);
        check_stop(o, reached);
        checkpoints.poll(co);
      }
      if (!pending.empty())
        throw RunError("every worker reported done, but snapshot " + std::to_string(pending.begin()->first) +
                       " lacks the bodies of some of them");
      out.wall_seconds = std::chrono::duration<double>(Clock::now() - start_clock).count();
      co.finish();
    } catch (const std::exception& e) {
      co.abort(error_text(e));
      throw;
    }
  }, [&] {
    if (!coupling.loose) return;
    const std::vector<CouplingRecord> records = coupling_log.records();
    if (stats) stats->coupling = records;
    if (sink) sink->write_coupling(records);
  });
  // Loose: the steps of the output grid's step, as run_loose counts them.
  out.steps = coupling.loose ? step_grid(o.t_start, o.t_end, o.step).steps : steps;
  out.rejected = rejected;
  out.evaluations = evaluations;
  out.final_state = std::move(y);
  return out;
}

}  // namespace mbsflow
