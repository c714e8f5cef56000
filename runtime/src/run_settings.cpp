#include "mbsflow/runtime/run_settings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/stepper.hpp"

namespace mbsflow {
namespace {

using R = RunRequest;
constexpr unsigned everywhere = in_cli | in_python | in_model;
constexpr unsigned front_ends = in_cli | in_python;
constexpr unsigned stepped = everywhere | in_simulation;  // also mbsflow.Simulation's

std::vector<std::string> method_names() {
  std::vector<std::string> out;
  for (const StepperEntry& e : stepper_entries()) out.push_back(e.method.name());
  return out;
}

// A positive real, a non-negative real, an integer range.
RunSetting positive(RunSetting s) {
  s.lo = 0.0;
  s.lo_open = true;
  return s;
}
RunSetting non_negative(RunSetting s) {
  s.lo = 0.0;
  return s;
}
RunSetting range(RunSetting s, double lo, double hi) {
  s.lo = lo;
  s.hi = hi;
  return s;
}
RunSetting one_of(RunSetting s, std::vector<std::string> choices) {
  s.choices = std::move(choices);
  return s;
}

std::vector<RunSetting> declare() {
  std::vector<RunSetting> s;
  // The model's simulation block.
  s.push_back({"t_start", "", in_model, &R::t_start, "Start time in s (default 0)"});
  s.push_back({"t_end", "--t-end", stepped, &R::t_end, "End time in s (default 1); must be after the model's t_start"});
  s.push_back(positive({"step", "--step", stepped, &R::step,
                        "Step in s; RK4 default: the stability estimate from the stiffest joint; the adaptive methods' "
                        "first step"}));
  RunSetting method{"method", "--method", stepped, &R::method,
                    "Integration method (default: rk4 where a joint gives it a stable step, tirk for beams, else dopri5)"};
  method.choices_of = method_names;
  s.push_back(method);
  s.push_back({"variant", "--variant", stepped, &R::variant,
               "tirk: tableau and/or iteration, e.g. radau5 or radau3,newton-triangular (default radau3,newton); "
               "colloc: m,s[,order]; another {method} than the model's drops the model's variant"});
  RunSetting every = range({"output_every", "--every", everywhere, &R::output_every,
                            "Write every K-th step (default: about a thousand snapshots over the run)"},
                           1, 1 << 30);
  every.excludes = "output_interval";
  s.push_back(every);
  s.push_back(positive({"output_interval", "--output-interval", everywhere, &R::output_interval,
                        "Write every S s of model time, whatever the method's steps (replaces {output_every})"}));
  s.push_back(positive({"rtol", "--rtol", stepped, &R::rtol,
                        "Adaptive methods (dopri5, colloc, tirk): relative tolerance (default 1e-06)"}));
  s.push_back(positive({"atol", "--atol", stepped, &R::atol,
                        "Adaptive methods (dopri5, colloc, tirk): absolute tolerance (default 1e-08)"}));
  s.push_back({"assemble", "--assemble", everywhere, &R::assemble,
               "Move the bodies onto rigid joints that their initial positions violate (reported); without it such a "
               "model is refused with the joint and its violation"});
  // The implicit methods' linear algebra.
  s.push_back(one_of({"linear_solver", "--linear-solver", front_ends | in_simulation, &R::linear_solver,
                      "colloc, tirk: the Newton matrices' LU: auto (dense up to 100 equations, banded when narrow, else "
                      "klu), dense, banded, klu (SuiteSparse) or sparselu (Eigen)"},
                     {"auto", "dense", "banded", "klu", "sparselu"}));
  s.push_back(one_of({"jacobian", "--jacobian", front_ends | in_simulation, &R::jacobian,
                      "colloc, tirk: auto (analytic when every force comes from bushings, springs, compliant joints, "
                      "loads and gravity; else differences grouped by the pattern's colouring) or differences"},
                     {"auto", "differences"}));
  // Results.
  s.push_back({"output", "-o,--output", in_cli, &R::output,
               "Results file (HDF5, with an XDMF sidecar for ParaView); without it a final-state summary is printed. "
               "Replaces only an earlier results file (else {force})"});
  s.push_back({"force", "--force", in_cli, &R::force,
               "With {output}: replace the file there even if it is not an mbsflow results file"});
  s.push_back({"fields", "--fields", front_ends, &R::fields,
               "What to write: position, orientation, velocity, angular_velocity, energy, joint_force, or all (a model "
               "with beams adds joint_force unless told)"});
  s.push_back({"quiet", "-q,--quiet", in_cli, &R::quiet, "Print only warnings, errors and the closing line"});
  s.push_back({"timings", "--timings", in_cli, &R::timings,
               "Print each set-up phase's time and the memory held after it (resident, peak, bytes per body)"});
  // Threads and submodels.
  s.push_back(range({"threads", "--threads", front_ends | in_simulation, &R::threads, "Threads (0: all cores)"}, 0, 4096));
  RunSetting partitions = range({"partitions", "--partitions", front_ends, &R::partitions,
                                 "Submodels (default: one per thread, fewer for small models); results are the same "
                                 "bit for bit. Python's partition also takes a partition file"},
                                1, 1 << 30);
  partitions.python_name = "partition";
  s.push_back(partitions);
  s.push_back(one_of({"executor", "--executor", front_ends, &R::executor,
                      "flow: oneTBB flow graph, neighbours only; barrier: a barrier per stage (the classical scheme)"},
                     {"flow", "barrier"}));
  s.push_back({"partition_file", "--partition-file", in_cli, &R::partition_file,
               "Use the assignment written by mbsflow partition -o"});
  s.push_back(one_of({"partitioner", "--partitioner", front_ends, &R::partitioner,
                      "best, band (band cuts of the reverse Cuthill-McKee order) or metis; see mbsflow partition"},
                     {"best", "band", "metis"}));
  // Worker processes.
  RunSetting cluster{"cluster", "--cluster", in_cli, &R::cluster,
                     "Run on the workers of this cluster file (docs/cluster.md); this process coordinates and writes the "
                     "results"};
  cluster.excludes = "processes";
  s.push_back(cluster);
  s.push_back(range({"processes", "--processes", in_cli, &R::processes,
                     "Run on N worker processes on this host, started and stopped here (one submodel each unless "
                     "{partitions})"},
                    1, 1024));
  s.push_back(one_of({"transport", "--transport", in_cli, &R::transport, "With {processes}: tcp (loopback) or ipc"},
                     {"tcp", "ipc"}));
  RunSetting slurm{"slurm", "--slurm", in_cli, &R::slurm,
                   "Run as a task of a Slurm step (srun -N H -n N mbsflow run MODEL --slurm -o r.h5): task 0 coordinates "
                   "and writes the results, the other tasks serve as its workers; hosts from the step's node list, keys "
                   "from {slurm_key} (docs/cluster.md)"};
  slurm.excludes = "cluster,processes";
  s.push_back(slurm);
  RunSetting port = range({"slurm_port", "--slurm-port", in_cli, &R::slurm_port,
                           "With {slurm}: the first of the run's ports (task 0's results inbox; a task with local index l takes "
                           "base + 2l and base + 2l + 1); default 20000 + 40 (job id mod 1000)"},
                          1, 65535);
  port.needs = "slurm";
  s.push_back(port);
  RunSetting key{"slurm_key", "--slurm-key", in_cli, &R::slurm_key,
                 "With {slurm}: the key pair every task uses, STEM.key as written by mbsflow keygen STEM, in a folder the nodes share "
                 "(default $HOME/.mbsflow/cluster)"};
  key.needs = "slurm";
  s.push_back(key);
  RunSetting insecure{"insecure", "--insecure", in_cli, &R::insecure,
                      "With {cluster}: run without the cluster file's keys, on this host only (loopback endpoints): any local user who "
                      "can reach the ports could join the run"};
  insecure.needs = "cluster";
  s.push_back(insecure);
  RunSetting anywhere{"insecure_network", "--insecure-network", in_cli, &R::insecure_network,
                      "With {cluster}: run without keys on any network: only where everyone who can reach the ports is trusted"};
  anywhere.needs = "cluster";
  s.push_back(anywhere);
  s.push_back(non_negative({"exchange_delay", "--exchange-delay", in_cli, &R::exchange_delay,
                            "With {cluster} or {processes}: hold every boundary message back this many s (a slow "
                            "network, for tests)"}));
  // Loose coupling.
  s.push_back(one_of({"coupling", "--coupling", front_ends, &R::coupling,
                      "tight: neighbours exchange every stage (bitwise the one-thread run); loose: each submodel "
                      "integrates a macro step on its own with extrapolated neighbours (co-simulation)"},
                     {"tight", "loose"}));
  s.push_back(positive({"macro_step", "--macro-step", front_ends, &R::macro_step,
                        "Loose coupling: the exchange interval H in s, fixed (default: 16 RK4 stable steps, the first "
                        "and largest try of error control; with {max_lag}, a tenth of one)"}));
  s.push_back(non_negative({"coupling_tol", "--coupling-tol", front_ends, &R::coupling_tol,
                            "Loose coupling: take a macro step again, shorter, when the neighbours' bodies at the cut "
                            "are off by more than this many m (default 1e-06 without {max_lag} or {macro_step}, also "
                            "across processes, which all take the same macro steps); 0: fixed macro step"}));
  s.push_back(range({"max_lag", "--max-lag", front_ends, &R::max_lag,
                     "Loose coupling: a submodel may run up to L macro steps ahead of its slowest neighbour, taking the "
                     "newest neighbour values it has, while messages travel (results then depend on timing)"},
                    0, 1000));
  s.push_back({"exact_lag", "--exact-lag", front_ends, &R::exact_lag,
               "With {max_lag} L: take the neighbours' values exactly L macro steps back instead of the newest "
               "(repeatable whatever the timing)"});
  RunSetting methods{"submodel_methods", "--submodel-methods", front_ends, &R::submodel_methods,
                     "Loose coupling: each submodel's method, comma-separated in submodel order (rk4 with substeps of "
                     "{step}, dopri5 with its own steps), e.g. rk4,dopri5,rk4; default: {method} for all"};
  methods.choices_of = method_names;
  methods.list = true;
  methods.library_name = "methods";  // LooseOptions::methods
  s.push_back(methods);
  s.push_back({"overlap", "--overlap", front_ends, &R::overlap,
               "Loose coupling: each submodel also integrates the neighbours' bodies that a disturbance at the cut "
               "reaches within this many s, extrapolating only beyond them; 0: none (default: one macro step)"});
  s.push_back(range({"extrapolation", "--extrapolation", front_ends, &R::extrapolation,
                     "Loose coupling: order of the neighbours' extrapolation, 0, 1 or 2"},
                    0, 2));
  // Checkpoints.
  s.push_back(positive({"checkpoint_every", "--checkpoint-every", in_cli, &R::checkpoint_every,
                        "Write a checkpoint every S s of wall-clock time (between steps or macro steps; any method and "
                        "coupling, on threads or worker processes), to resume with --resume after a crash or kill"}));
  s.push_back({"checkpoint", "--checkpoint", in_cli, &R::checkpoint,
               "The checkpoint file (default: the results file's name + .ckpt)"});
  return s;
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string joined(const std::vector<std::string>& items, const char* between) {
  std::string out;
  for (const std::string& i : items) out += (out.empty() ? "" : between) + i;
  return out;
}

}  // namespace

std::vector<std::string> comma_items(std::string_view list) {
  std::vector<std::string> out;
  for (std::size_t at = 0; !list.empty() && at <= list.size();) {
    const std::size_t comma = std::min(list.find(',', at), list.size());
    out.emplace_back(list.substr(at, comma - at));
    at = comma + 1;
  }
  return out;
}

std::string RunSetting::long_flag() const {
  const std::string f = flag;
  const std::size_t comma = f.find(',');
  return comma == std::string::npos ? f : f.substr(comma + 1);
}

std::vector<std::string> RunSetting::allowed() const { return choices_of ? choices_of() : choices; }

bool RunSetting::optional() const {
  return std::holds_alternative<std::optional<double> RunRequest::*>(field) ||
         std::holds_alternative<std::optional<int> RunRequest::*>(field) ||
         std::holds_alternative<std::optional<std::string> RunRequest::*>(field);
}

bool RunSetting::is_flag() const { return std::holds_alternative<bool RunRequest::*>(field); }

bool RunSetting::is_integer() const {
  return std::holds_alternative<std::optional<int> RunRequest::*>(field) || std::holds_alternative<int RunRequest::*>(field);
}

bool RunSetting::is_number() const {
  return is_integer() || std::holds_alternative<std::optional<double> RunRequest::*>(field) ||
         std::holds_alternative<double RunRequest::*>(field);
}

const std::vector<RunSetting>& run_settings() {
  static const std::vector<RunSetting> settings = declare();
  return settings;
}

const RunSetting* find_run_setting(std::string_view name) {
  for (const RunSetting& s : run_settings())
    if (name == s.name || (s.library_name && name == s.library_name)) return &s;
  return nullptr;
}

std::string setting_error(const RunSetting& s, double v) {
  if (!std::isfinite(v)) return "must be a finite number";
  if (s.is_integer() && v != std::floor(v)) return "must be an integer";
  if (s.lo_open && !(v > s.lo)) return "must be > " + number_text(s.lo);
  if (!(v >= s.lo)) return "must be >= " + number_text(s.lo);
  if (!(v <= s.hi)) return "must be <= " + number_text(s.hi);
  return "";
}

std::string setting_error(const RunSetting& s, const std::string& value) {
  const std::vector<std::string> allowed = s.allowed();
  if (allowed.empty()) return "";
  const std::vector<std::string> items = s.list ? comma_items(value) : std::vector<std::string>{value};
  std::string noun = s.list ? "method" : s.name;  // the one list setting lists methods
  for (char& c : noun) c = c == '_' ? ' ' : c;
  for (const std::string& item : items)
    if (std::find(allowed.begin(), allowed.end(), item) == allowed.end())
      return "unknown " + noun + (s.list ? " '" + item + "'" : "") + " (" + joined(allowed, ", ") + ")";
  return "";
}

std::string default_text(const RunSetting& s) {
  if (s.optional()) return "";
  const RunRequest r;
  // A number outside its range (0 for checkpoint_every) stands for none.
  bool none = false;
  std::visit(
      [&](auto member) {
        const auto& v = r.*member;
        if constexpr (std::is_arithmetic_v<std::decay_t<decltype(v)>> && !std::is_same_v<std::decay_t<decltype(v)>, bool>)
          none = !setting_error(s, static_cast<double>(v)).empty();
      },
      s.field);
  if (none) return "";
  return std::visit(
      [&](auto member) -> std::string {
        const auto& v = r.*member;
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, bool>) return v ? "true" : "false";
        else if constexpr (std::is_same_v<V, std::string>) return v;
        else if constexpr (std::is_same_v<V, int>) return std::to_string(v);
        else if constexpr (std::is_same_v<V, double>) return number_text(v);
        else return "";
      },
      s.field);
}

std::string run_settings_table() {
  auto name_of = [](const std::string& n, const std::string*) {
    const RunSetting* s = find_run_setting(n);
    return "`" + (s && *s->flag ? s->long_flag() : n) + "`";
  };
  std::string out = "| flag | Python | model | default | values | what it does |\n|---|---|---|---|---|---|\n";
  for (const RunSetting& s : run_settings()) {
    std::string values;
    if (!s.allowed().empty())
      values = joined(s.allowed(), ", ") + (s.list ? " (a list)" : "");
    else if (s.is_flag())
      values = "on or off";
    else if (s.is_number()) {
      const std::string kind = s.is_integer() ? "integer" : "number";
      if (s.lo_open)
        values = kind + " > " + number_text(s.lo);
      else if (std::isfinite(s.lo) && std::isfinite(s.hi))
        values = kind + " " + number_text(s.lo) + " .. " + number_text(s.hi);
      else if (std::isfinite(s.lo))
        values = kind + " >= " + number_text(s.lo);
      else
        values = kind;
    } else {
      values = "text";
    }
    const std::string flag = *s.flag ? "`" + std::string(s.flag) + "`" : "";
    const std::string py = s.places & in_python ? "`" + std::string(s.keyword()) + "`" +
                                                      (s.places & in_simulation ? ", Simulation" : "")
                                                : "";
    const std::string model = s.places & in_model ? "`simulation." + std::string(s.name) + "`" : "";
    std::string also;
    if (*s.excludes) {
      std::string names;
      for (const std::string& other : comma_items(s.excludes))
        names += (names.empty() ? "" : ", ") + render("{" + other + "}", name_of);
      also += " Not with " + names + ".";
    }
    const std::string d = default_text(s);
    out += "| " + flag + " | " + py + " | " + model + " | " + (d.empty() ? "" : "`" + d + "`") + " | " + values + " | " +
           render(s.help, name_of) + "." + also + " |\n";
  }
  return out;
}

}  // namespace mbsflow
