// mbsflow plan MODEL.json --hosts H --threads T: what a tightly coupled run will cost per
// step on H hosts of T threads, and its speedup, before any run: the model's own cost
// per step measured here on one thread (a short run), the cut a cluster run makes, and
// the seed's performance model of the exchange between hosts (Hockney).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "exchange_cost.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/run_request.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "run_prediction.hpp"

namespace mbsflow::cli {
namespace {

struct PlanArgs {
  std::string model;
  int hosts = 1, threads = 1;
  std::string method;
  std::optional<double> step, t_end;
  std::optional<double> alpha_us, bandwidth_mbs;
  std::string network = "gbe";
  std::string csv;
};

// The methods whose stages the hosts of a tightly coupled run exchange (their registry
// entries have a stage scheme), and the same as "rk4 or dopri5".
std::vector<std::string> tight_methods() {
  std::vector<std::string> names;
  for (const StepperEntry& e : stepper_entries())
    if (has_stage_scheme(e)) names.emplace_back(e.method.name());
  return names;
}

std::string tight_method_list() { return method_names(has_stage_scheme, "or"); }

struct Measured {
  double seconds_per_stage = 0.0;  // one right-hand side with its share of the integrator's work
  double stages_per_step = 0.0;
};

// Short runs on one thread: longer until one takes a fifth of a second, then the fastest
// of three of that length (the first touches its memory for the first time, and this
// machine may be shared).
Measured measure_one_thread(const Model& m, RunOptions o) {
  MultibodySystem sys(m);
  const auto timed = [&](long steps) {
    o.t_end = o.t_start + static_cast<double>(steps) * o.step;
    o.output_every = static_cast<int>(steps);
    o.output_interval = 0.0;
    return run_simulation(sys, o, nullptr);
  };
  long steps = 2;
  RunSummary r = timed(steps);
  while (r.wall_seconds < 0.2 && steps < (1L << 24)) r = timed(steps *= 4);
  for (int again = 0; again < 2; ++again) {
    const RunSummary next = timed(steps);
    if (next.wall_seconds < r.wall_seconds) r = next;
  }
  return {r.wall_seconds / static_cast<double>(r.evaluations),
          static_cast<double>(r.evaluations) / static_cast<double>(std::max(1L, r.steps))};
}

// The network's Hockney figures, and how they were come by, for the table's header.
Hockney network_model(const PlanArgs& a, std::string& described) {
  Hockney h;
  std::vector<std::string> how;
  if (!a.alpha_us || !a.bandwidth_mbs) {
    h = fit_loopback_tcp();
    char line[160];
    std::snprintf(line, sizeof line, "tcp on loopback measured: alpha %.1f us, beta %.0f MB/s", 1e6 * h.alpha, h.beta / 1e6);
    how.push_back(line);
    if (a.network == "gbe") {
      h = gigabit_ethernet(h);
      how.push_back("Gigabit Ethernet assumed: +" + std::to_string(static_cast<int>(1e6 * gbe_extra_latency_s)) +
                    " us, at most " + std::to_string(static_cast<int>(gbe_bytes_per_s / 1e6)) + " MB/s");
    }
  }
  if (a.alpha_us) h.alpha = *a.alpha_us * 1e-6, how.push_back("alpha given");
  if (a.bandwidth_mbs) h.beta = *a.bandwidth_mbs * 1e6, how.push_back("beta given");
  for (const std::string& part : how) described += (described.empty() ? "" : "; ") + part;
  return h;
}

int plan(const PlanArgs& a) {
  Model m = read_model_file(a.model);
  RunRequest overrides;
  overrides.step = a.step;
  overrides.t_end = a.t_end;
  if (!a.method.empty()) overrides.method = a.method;
  apply_overrides(m, overrides);
  RunOptions o = options_from_model(m);
  if (stepper_entry(o.method).tight_stages == 0)
    throw InputError("plan: runs across hosts integrate with " + tight_method_list() + ", this model asks for " +
                     o.method.name() + "; give --method " + tight_method_list());
  if (!std::isfinite(o.step)) throw InputError(a.model + ": no joints to estimate a step from; give --step");
  std::string net_text;
  const Hockney net = network_model(a, net_text);
  const Measured one = measure_one_thread(m, o);
  const double seconds_per_cost = one.seconds_per_stage / decompose(m, 1).estimated_time();
  const bool adaptive = stepper_entry(o.method).adaptive;
  const double steps = adaptive ? 0.0 : std::ceil((o.t_end - o.t_start) / o.step * (1.0 - 1e-12));
  std::printf("model %s: %zu bodies, %zu joints; %s, step %.4g s%s\n", m.name.c_str(), m.bodies.size(), m.joints.size(),
              o.method.name(), o.step, adaptive ? " (first step; adaptive)" : "");
  std::printf("measured on this host, one thread (fastest of 3 runs): %.1f us per step (%.0f right-hand sides of %.1f us, %.1f ns per body)\n",
              1e6 * one.seconds_per_stage * one.stages_per_step, one.stages_per_step, 1e6 * one.seconds_per_stage,
              1e9 * one.seconds_per_stage / static_cast<double>(m.bodies.size()));
  std::printf("exchange between hosts: alpha %.1f us, beta %.0f MB/s (%s)\n", 1e6 * net.alpha, net.beta / 1e6, net_text.c_str());
  std::printf("not modelled: memory bandwidth shared by a host's threads, the flow graph's scheduling, the results' output\n\n");

  std::ofstream csv;
  if (!a.csv.empty()) {
    csv.open(a.csv);
    if (!csv) throw InputError("--csv: cannot write " + a.csv);
    csv << "hosts,threads,submodels,cut_joints,imbalance,compute_s_per_stage,exchange_s_per_stage,messages_per_stage,"
           "bytes_per_stage,s_per_step,speedup,efficiency,run_s\n";
  }
  std::printf("%6s %8s %10s %8s %10s %12s %12s %10s %12s %8s %10s %10s\n", "hosts", "threads", "submodels", "cut", "imbalance",
              "compute us", "exchange us", "messages", "us per step", "speedup", "efficiency", "run s");
  const double t1 = one.seconds_per_stage * one.stages_per_step;
  std::vector<std::pair<int, int>> rows{{1, 1}};
  for (int h = 1; h < a.hosts; h *= 2) rows.emplace_back(h, a.threads);
  rows.emplace_back(a.hosts, a.threads);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto [hosts, threads] = rows[i];
    if (i > 0 && rows[i] == rows[i - 1]) continue;
    const StagePrediction p = predict_stage(decompose(m, hosts * threads), hosts, threads, seconds_per_cost, net);
    const double per_step = p.stage_s() * one.stages_per_step, speedup = t1 / per_step;
    char run_s[32] = "";
    if (steps > 0) std::snprintf(run_s, sizeof run_s, "%.4g", per_step * steps);
    std::printf("%6d %8d %10d %8d %9.1f%% %12.1f %12.1f %10d %12.1f %8.2f %10.2f %10s\n", hosts, threads, hosts * threads,
                p.cut_joints, 100.0 * p.imbalance, 1e6 * p.compute_s, 1e6 * p.exchange_s, p.messages, 1e6 * per_step, speedup,
                speedup / (hosts * threads), run_s);
    if (csv.is_open())
      csv << hosts << ',' << threads << ',' << hosts * threads << ',' << p.cut_joints << ',' << p.imbalance << ','
          << p.compute_s << ',' << p.exchange_s << ',' << p.messages << ',' << p.bytes << ',' << per_step << ',' << speedup
          << ',' << speedup / (hosts * threads) << ',' << (steps > 0 ? per_step * steps : 0.0) << '\n';
  }
  if (steps > 0) std::printf("\nrun s: %.0f steps to t_end %.4g s\n", steps, o.t_end);
  if (!a.csv.empty()) std::printf("written to %s\n", a.csv.c_str());
  return 0;
}

}  // namespace

Action add_plan(CLI::App& app) {
  auto a = std::make_shared<PlanArgs>();
  CLI::App* sub = app.add_subcommand(
      "plan", "Predict a run's time per step and speedup on H hosts of T threads before running it (measured cost per body, "
              "Hockney exchange model)");
  sub->add_option("model", a->model, "Model file (JSON)")->required();
  sub->add_option("--hosts", a->hosts, "Hosts (worker processes), one submodel per thread each")->check(CLI::Range(1, 4096));
  sub->add_option("--threads", a->threads, "Threads per host")->check(CLI::Range(1, 4096));
  sub->add_option("--method", a->method, tight_method_list() + " (default: the model's)")
      ->check(CLI::IsMember(tight_methods()));
  sub->add_option("--step", a->step, "Step in s (default: the model's, or the RK4 stability estimate)")->check(CLI::PositiveNumber);
  sub->add_option("--t-end", a->t_end, "End time in s, for the predicted run time")->check(CLI::PositiveNumber);
  sub->add_option("--network", a->network,
                  "gbe: the tcp cost measured on loopback plus Gigabit Ethernet's latency and rate; loopback: as measured")
      ->check(CLI::IsMember({"gbe", "loopback"}))
      ->capture_default_str();
  sub->add_option("--alpha-us", a->alpha_us, "Latency of one message in us (Hockney alpha), instead of the network's")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--bandwidth-mbs", a->bandwidth_mbs, "Bandwidth in MB/s (Hockney beta), instead of the network's")
      ->check(CLI::PositiveNumber);
  sub->add_option("--csv", a->csv, "Also write the table as CSV");
  return [a] { return plan(*a); };
}

}  // namespace mbsflow::cli
