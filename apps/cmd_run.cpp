// mbsflow run MODEL.json: one simulation on this process.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <future>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "huge_pages.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/words.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "local_workers.hpp"
#include "slurm_launch.hpp"
#include "mbsflow/io/checkpoint_file.hpp"
#include "mbsflow/io/cluster_file.hpp"
#include "mbsflow/io/file_text.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/io/partition_file.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/partitioned_run.hpp"
#include "mbsflow/runtime/run.hpp"
#include "mbsflow/runtime/run_request.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "phase_timings.hpp"
#include "progress.hpp"
#include "run_flags.hpp"
#include "mbsflow/runtime/stop_signals.hpp"

namespace mbsflow::cli {
namespace {

// The settings (mbsflow/runtime/run_settings.hpp) with the model file and --resume.
struct RunArgs : RunRequest {
  std::string model;
  bool output_given = false;  // -o "" is refused, not taken as no -o
  std::string resume;         // a checkpoint file to go on from
};

// How many bodies the submodels of a loose run borrow, all together.
std::size_t borrowed_bodies(const Model& m, const Decomposition& d, const LooseOptions& lo) {
  std::size_t n = 0;
  for (const Submodel& s : loose_decomposition(m, d, lo).submodels) n += s.borrowed.size();
  return n;
}

// The closing lines of a loosely coupled run: its coupling errors, lags and macro steps.
void print_coupling(const LooseStats& ls, bool adaptive, int max_lag, double tol, bool cluster) {
  char adapt[128] = "", lag[96] = "";
  if (adaptive && ls.over_tolerance > 0)
    std::fprintf(stderr,
                 "mbsflow: warning: %ld macro steps kept a coupling error above --coupling-tol %.3g m at the smallest "
                 "macro step (1/1024 of --macro-step); a larger --overlap may help\n",
                 ls.over_tolerance, tol);
  if (!adaptive && tol > 0.0 && ls.max_position_error > tol)
    std::fprintf(stderr,
                 "mbsflow: warning: the coupling error %.3g m is above %.3g m with a fixed macro step: give a "
                 "smaller --macro-step, a larger --overlap or --coupling-tol\n",
                 ls.max_position_error, tol);
  if (adaptive && cluster)  // the workers do not report how many they took again
    std::snprintf(adapt, sizeof adapt, "; macro step %.3g .. %.3g s", ls.smallest_macro_step, ls.largest_macro_step);
  else if (adaptive)
    std::snprintf(adapt, sizeof adapt, "; macro step %.3g .. %.3g s, %ld taken again", ls.smallest_macro_step,
                  ls.largest_macro_step, ls.rejected);
  if (max_lag > 0) {
    long lagged = 0;
    for (int l : ls.lag) lagged += l > 0 ? 1 : 0;
    std::snprintf(lag, sizeof lag, "; %ld macro steps from older values, at most %d steps old", lagged, ls.largest_lag);
  }
  std::fprintf(stderr, "mbsflow: coupling error over %ld macro steps: ghost positions off by at most %.3g m, last %.3g m%s%s\n",
               ls.macro_steps, ls.max_position_error, ls.position_error.empty() ? 0.0 : ls.position_error.back(), adapt, lag);
}

// How the run is cut: a partition file, --partitions, or default_k submodels (none when
// that is 1 and the run is a tight one in one process).
std::optional<Decomposition> choose_decomposition(const Model& m, const RunArgs& a, int default_k, bool plain_if_one) {
  if (!a.partition_file.empty()) return read_partition_file(m, a.partition_file);
  return cut_for_run(m, a.partitions, default_k, partitioner_named(a.partitioner), plain_if_one);
}

std::string human_bytes(double b) {
  const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024.0 && u < 4) {
    b /= 1024.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g %s", b, unit[u]);
  return buf;
}

// Says in one line which method and step were chosen where the model and the flags leave
// them open (a warning for a given RK4 step above the stability estimate s of the model).
void say_options(const Model& m, const RunArgs& a, const StableStep& s, const RunOptions& o) {
  const char* name = method_name(o.method);
  if (m.simulation.step) {
    if (!stepper_entry(o.method).adaptive && *m.simulation.step > s.step)
      std::fprintf(stderr, "mbsflow: warning: step %.3g s is above the estimated RK4 stability limit %s\n",
                   *m.simulation.step, s.describe(m).c_str());
    return;
  }
  if (a.quiet) return;
  char tolerances[64];
  std::snprintf(tolerances, sizeof tolerances, "rtol %.3g, atol %.3g", o.rtol, o.atol);
  if (o.method_chosen && !m.beams.empty()) {
    std::fprintf(stderr, "mbsflow: beams are stiff: %s, adaptive, %s (--method, --step, --rtol and --atol choose)\n", name,
                 tolerances);
  } else if (o.method_chosen && o.method != Method::rk4) {
    std::fprintf(stderr,
                 "mbsflow: no joint gives RK4 a stable step (no compliant joint): %s, adaptive, %s (--method, --step, "
                 "--rtol and --atol choose)\n", name, tolerances);
  } else if (stepper_entry(o.method).implicit) {
    std::fprintf(stderr, "mbsflow: no step given: %s picks its first step from the tolerances (%s)\n", name, tolerances);
  } else if (stepper_entry(o.method).adaptive) {
    std::fprintf(stderr, "mbsflow: no step given: %s starts with %.4g s (%s) and adapts it to %s\n", name, o.step,
                 std::isfinite(s.step) ? "the RK4 stability estimate" : "a thousandth of the run", tolerances);
  } else {
    char fit[96] = "", every[64] = "";
    if (o.step != s.step) std::snprintf(fit, sizeof fit, ", shortened to %.4g s to fit the output interval", o.step);
    if (!m.simulation.output_every && o.output_interval <= 0.0 && o.output_every > 1)
      std::snprintf(every, sizeof every, "; a snapshot every %d steps", o.output_every);
    std::fprintf(stderr, "mbsflow: no step given: RK4 with the stability estimate %s%s%s\n", s.describe(m).c_str(), fit,
                 every);
  }
}

// InputError naming the file for rigid joints that the initial positions violate (unless
// assembly was asked for) or that cannot be assembled; with `report`, which bodies the
// assembly moves, and how far (--assemble).
void check_assembly(const std::shared_ptr<Model>& model, const std::string& file, bool report) {
  const Model& m = *model;
  MultibodySystem sys(model, static_cast<int>(m.bodies.size()));
  Eigen::VectorXd y;
  try {
    y = sys.initial_state();
  } catch (const ModelError& e) {
    throw InputError(file + ": " + e.text());
  }
  if (!report) return;
  const StateLayout& l = sys.layout();
  std::string moved;
  int count = 0;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const Eigen::Vector3d given(m.bodies[i].position[0], m.bodies[i].position[1], m.bodies[i].position[2]);
    const double d = (y.segment<3>(l.position(k)) - given).norm();
    if (!(d > SimulationSettings::assembly_tolerance)) continue;
    if (++count <= 10) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s%s by %.3g m", count > 1 ? ", " : "", m.bodies[i].name.c_str(), d);
      moved += buf;
    }
  }
  if (count == 0)
    std::fprintf(stderr, "mbsflow: --assemble: the rigid joints hold as given; no body moved\n");
  else
    std::fprintf(stderr, "mbsflow: --assemble moved %d %s onto the rigid joints: %s%s\n", count,
                 count == 1 ? "body" : "bodies", moved.c_str(), count > 10 ? ", ..." : "");
}

void print_summary(const Model& m, MultibodySystem& sys, const RunOptions& o, const RunSummary& r) {
  const Energy e0 = sys.energy(o.t_start, sys.initial_state());
  const Energy e1 = sys.energy(o.t_end, r.final_state);
  const StateLayout& l = sys.layout();
  std::printf("model %s: %s, %s; %s, step %.4g s, t = %g..%g s\n", m.name.c_str(),
              count_of(static_cast<long long>(m.bodies.size()), "body", "bodies").c_str(),
              count_of(static_cast<long long>(m.joints.size()), "joint").c_str(), method_name(o.method), o.step, o.t_start, o.t_end);
  std::printf("energy (kinetic + gravity + elastic): initial %.10g J, final %.10g J\n", e0.total(), e1.total());
  const std::size_t shown = std::min<std::size_t>(m.bodies.size(), 10);
  std::printf("final state of %s%s:\n", shown < m.bodies.size() ? "the first " : "",
              shown == 1 ? "the body" : count_of(static_cast<long long>(shown), "body", "bodies").c_str());
  std::printf("  %-16s %14s %14s %14s %14s %14s %14s\n", "body", "x", "y", "z", "vx", "vy", "vz");
  for (std::size_t i = 0; i < shown; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const auto& y = r.final_state;
    std::printf("  %-16s %14.6g %14.6g %14.6g %14.6g %14.6g %14.6g\n", m.bodies[i].name.c_str(), y[l.position(k)],
                y[l.position(k) + 1], y[l.position(k) + 2], y[l.velocity(k)], y[l.velocity(k) + 1], y[l.velocity(k) + 2]);
  }
}

// The arguments after "run" of this process's command line, for a checkpoint.
std::vector<std::string> run_arguments() {
  const std::vector<std::string>& all = invocation_arguments();
  const auto at = std::find(all.begin(), all.end(), std::string("run"));
  return at == all.end() ? std::vector<std::string>{} : std::vector<std::string>(at + 1, all.end());
}

std::string checkpoint_path(const RunArgs& a) {
  if (!a.checkpoint.empty()) return a.checkpoint;
  if (a.output.empty()) throw InputError("--checkpoint-every: give -o FILE (the checkpoint is FILE.ckpt) or --checkpoint FILE");
  return a.output + ".ckpt";
}

// resumed: the checkpoint to go on from (its path in resumed_path), whose model text
// replaces the model file's.
int run(const RunArgs& a, const CheckpointFile* resumed = nullptr, const std::string& resumed_path = "") {
  if (a.model.empty()) throw InputError("run: give a MODEL file, or --resume CHECKPOINT to go on with a run");
  std::optional<SlurmLaunch> slurm;
  if (a.slurm) {
    slurm = slurm_launch(a.slurm_port, a.slurm_key);
    if (slurm->step.rank > 0) return serve_slurm_task(*slurm, a.threads, a.quiet);  // reads no model
  }
  const bool slurm_workers = slurm && slurm->step.tasks() > 1;
  // Before anything is read or started: a results path that would write over the model,
  // a folder, a device or another file is refused (a resumed run writes on in its own file).
  if (a.output_given || !a.output.empty())
    check_output_path(a.output, {{a.model, a.partition_file, a.cluster, resumed_path}, a.force});
  PhaseTimings timings(a.timings);
  // The file is mapped, not copied, and let go once parsed; only checkpoints keep its text.
  std::optional<FileText> file;
  if (!resumed) file.emplace(a.model, "model file", max_model_bytes);
  const std::string_view source = resumed ? std::string_view(resumed->model_text) : file->text();
  timings.mark("read the model file");
  // Held shared: the run's systems share it rather than copy it.
  const auto model = std::make_shared<Model>(read_model_text(source, a.model));
  Model& m = *model;
  const long bodies = static_cast<long>(m.bodies.size());
  timings.mark("parse and check the model", bodies);
  std::string model_text = a.checkpoint_every > 0.0 ? std::string(source) : std::string();
  file.reset();
  apply_overrides(m, a);
  // Rigid joints that the bodies do not meet are refused before anything else is said.
  if (std::any_of(m.joints.begin(), m.joints.end(), [](const Joint& j) { return is_kinematic(j.type) && j.rigid; }))
    check_assembly(model, resumed ? resumed_path : a.model, m.simulation.assemble && !a.quiet);
  const SettledRun settled = settle_run(m, a);
  const StableStep& stable = settled.stable;
  RunOptions o = settled.options;
  say_options(m, a, stable, o);
  timings.mark("stable step and options", bodies);
  FieldSet fields = a.output.empty() ? FieldSet{} : parse_fields(a.fields);
  // A model with beams writes their section forces unless told which fields to write.
  if (!a.output.empty() && !m.beams.empty() && a.fields == RunArgs{}.fields) fields.joint_force = true;
  const int threads = settled.threads;
  const bool cluster = !a.cluster.empty() || a.processes > 0 || slurm_workers;
  // The model's text for the results file and the worker processes is written on a
  // thread of its own while the run is cut and set up (1.4 s for a million-body model).
  // Nothing changes the model from here on.
  std::future<std::string> model_json;
  if (!a.output.empty() || cluster) model_json = std::async(std::launch::async, [&m] { return model_to_json(m); });
  const bool loose = settled.loose.has_value();
  if (a.exchange_delay > 0.0 && !cluster) throw InputError("{exchange_delay}: only with {cluster} or {processes}");
  const LooseOptions lo = settled.loose.value_or(LooseOptions{});
  const double macro_step = lo.macro_step;
  const ClusterCoupling coupling{loose ? &lo : nullptr, a.exchange_delay};
  if (cluster) check_cluster_run(m, o, coupling);  // before any worker is started
  std::optional<LocalWorkers> local;
  ClusterConfig cc;
  if (!a.cluster.empty()) {
    cc = read_cluster_file(a.cluster);
    cc.insecure = a.insecure_network ? Insecure::anywhere : a.insecure ? Insecure::loopback : Insecure::no;
    check_cluster_security(cc);  // before the run is set up
  }
  if (slurm_workers) {
    cc = slurm_cluster(slurm->step, slurm->base_port, slurm->keys);
    check_cluster_security(cc);
  } else if (slurm && !a.quiet) {
    std::fprintf(stderr, "mbsflow: --slurm with one task: a run on this process's threads\n");
  }
  // Loose coupling cuts the model even into one submodel (then it is a plain run).
  // Local workers take a submodel each; the model is cut before they are started, so that a
  // model that cannot be cut so far is refused before any process exists.
  const int default_k = a.processes > 0 ? a.processes
                        : cluster       ? cluster_submodels(cc)
                                        : default_submodels(m, o.method, loose, threads);
  std::optional<Decomposition> d;
  try {
    d = choose_decomposition(m, a, default_k, !cluster && !loose);
  } catch (const InputError& e) {
    if (a.processes == 0) throw;
    throw InputError("--processes " + std::to_string(a.processes) + " needs as many submodels: " + e.text() +
                     "; or run on threads (no --processes)");
  }
  if (a.processes > 0) {
    // Each worker gets its share of the cores unless --threads says how many.
    local.emplace(a.processes, a.transport, a.threads > 0 ? a.threads : std::max(1, threads / a.processes));
    cc = local->cluster();
  }

  give_back_free_memory();  // what reading and cutting the model freed, before the submodels are built
  timings.mark("cut into submodels", bodies);
  if (cluster && !a.quiet) {
    char coupling[96] = "";
    if (loose) std::snprintf(coupling, sizeof coupling, ", loosely coupled: macro step %.4g s", macro_step);
    std::fprintf(stderr, "mbsflow: %zu submodels on %zu worker processes (%s), %d cut joints, load imbalance %.1f %%%s\n",
                 d->submodels.size(), cc.workers.size(), cc.transport.c_str(), d->cut_joints, 100.0 * d->imbalance, coupling);
  }
  else if (loose && !a.quiet && d->submodels.size() == 1)
    std::fprintf(stderr, "mbsflow: 1 submodel: nothing to couple loosely, a plain run (--partitions N cuts the model "
                         "into N submodels)\n");
  else if (loose && !a.quiet)
    std::fprintf(stderr,
                 "mbsflow: %zu submodels on %d threads, loosely coupled: macro step %.4g s (%.3g x the cut joints' "
                 "RK4 stable step), extrapolation order %d, overlap %.4g s (%zu bodies borrowed)%s\n",
                 d->submodels.size(), threads, macro_step, macro_step / cut_joint_stable_step(m, *d), a.extrapolation,
                 overlap_reach(lo), borrowed_bodies(m, *d, lo), lo.coupling_tol > 0.0 ? ", error control" : "");
  else if (d && !a.quiet)
    std::fprintf(stderr, "mbsflow: %zu submodels on %d threads (%s), %d cut joints, load imbalance %.1f %%\n",
                 d->submodels.size(), threads, a.executor == "flow" ? "flow graph" : "barrier per stage", d->cut_joints,
                 100.0 * d->imbalance);
  if (stepper_entry(o.method).implicit && !loose && !cluster && !a.quiet) {  // an implicit method on the whole model
    std::string why;
    if (o.jacobian == "differences")
      std::fprintf(stderr, "mbsflow: Jacobian by coloured differences (--jacobian differences)\n");
    else if (has_analytic_jacobian(m, &why))
      std::fprintf(stderr, "mbsflow: analytic Jacobian\n");
    else
      std::fprintf(stderr, "mbsflow: Jacobian by coloured differences: no analytic one for %s\n", why.c_str());
  }
  ProgressLine progress(o.t_start, o.t_end, !a.quiet);
  o.progress = [&](double t, long steps) { progress.update(t, steps); };
  // After each phase of the set-up: building the submodels frees the copies of their joints
  // (on worker threads, in arenas the first evaluation's workspaces do not all reuse). Not
  // after the steps: nothing large is allocated after them, and trimming a heap that a
  // thousand snapshots went through took 0.15-0.3 s, a third of a 1 s run.
  o.phase = [&](const char* phase, RunPhase kind) {
    if (kind != RunPhase::steps) give_back_free_memory();
    if (a.timings) timings.mark(phase, bodies);
  };
  o.stop = install_stop_handlers();
  // Checkpoints: the file holds the arguments, folder and model text with the run's state.
  Checkpointing checkpointing;
  CheckpointFile checkpoint_file;
  long checkpoints = 0;
  std::string checkpoint_at;
  if (a.checkpoint_every > 0.0) {
    checkpoint_at = checkpoint_path(a);
    checkpoint_file.arguments = resumed ? resumed->arguments : run_arguments();
    checkpoint_file.directory = resumed ? resumed->directory : std::filesystem::current_path().string();
    checkpoint_file.model_text = std::move(model_text);
    checkpointing.every_s = a.checkpoint_every;
    checkpointing.write = [&](std::vector<std::uint8_t>&& state) {
      checkpoint_file.state = std::move(state);
      write_checkpoint_file(checkpoint_at, checkpoint_file);
      ++checkpoints;
    };
  }
  if (resumed) {
    checkpointing.resume = resumed->state;
    checkpointing.resume_from = "checkpoint " + resumed_path;
    if (!a.quiet) std::fprintf(stderr, "mbsflow: going on from checkpoint %s\n", resumed_path.c_str());
  }
  if (checkpointing.write || resumed) o.checkpoint = &checkpointing;
  std::string text = model_json.valid() ? model_json.get() : std::string();
  timings.mark("the model's text (written alongside)", bodies);
  std::unique_ptr<AsyncSink> sink;
  if (!a.output.empty()) {
    RunInfo info{cluster ? text : std::move(text), method_name(o.method), o.step, o.t_start, o.t_end, o.output_every,
                 invocation()};
    info.output_interval = o.output_interval;
    auto h5 = std::make_unique<Hdf5Sink>(a.output, fields, std::move(info));
    // The model's text goes to disk now rather than being held while the run is set up.
    if (!resumed) h5->prepare();
    sink = std::make_unique<AsyncSink>(std::move(h5));
    sink->set_stop(o.stop);
    timings.mark("open the results file, the model's text written", bodies);
  }
  RunPlan plan;
  plan.options = o;
  plan.partition = d;
  if (loose) plan.loose = lo;
  plan.parallel = settled.parallel;
  if (cluster) {
    plan.cluster = cc;
    plan.model_json = std::move(text);
    plan.exchange_delay_s = a.exchange_delay;
  }
  RunSummary r;
  try {
    RunStats stats;
    timings.mark("prepare the run", bodies);
    r = mbsflow::run(std::shared_ptr<const Model>(model), plan, sink.get(), &stats);
    timings.mark("the run's end", bodies);
    if (cluster) {
      stats.loose.records = stats.cluster.coupling;
      summarise_records(stats.loose);
    }
    if (loose && !a.quiet && d->submodels.size() > 1) print_coupling(stats.loose, lo.coupling_tol > 0.0, a.max_lag,
                                              a.coupling_tol.value_or(default_coupling_tol), cluster);
  } catch (const ModelError& e) {
    progress.finish();
    throw InputError((resumed ? resumed_path : a.model) + ": " + e.text());
  } catch (const RunError& e) {
    progress.finish();
    const int sig = stop_signal();
    throw RunError(e.text() + (sig == SIGTERM ? " (SIGTERM)" : sig == SIGINT ? " (SIGINT)" : "") +
                   (sink ? (sink->stats().snapshots > 0 ? " in " + a.output : "; no results file was written") : ""));
  }
  progress.finish();
  if (!a.quiet && !sink) {
    MultibodySystem sys(model, static_cast<int>(m.bodies.size()));  // shares the model: a copy is 450 B per body or more
    print_summary(m, sys, o, r);
  }
  const double body_steps = static_cast<double>(r.steps) * static_cast<double>(m.bodies.size());
  std::string output;
  if (sink) {
    const double bytes = static_cast<double>(std::filesystem::file_size(a.output));
    output = ", " + std::to_string(r.snapshots) + " snapshots, " + human_bytes(bytes) + " in " + a.output;
    if (sink->stats().waits > 0)
      output += " (the writer held the run back " + std::to_string(sink->stats().waits) + " times)";
  }
  const std::string newton = r.jacobians > 0 ? " (" + std::to_string(r.jacobians) + " Jacobians, " +
                                                   std::to_string(r.factorizations) + " factorisations)"
                                             : "";
  if (r.resumed_at) {
    char from[96];
    std::snprintf(from, sizeof from, "; went on from the checkpoint at t = %.6g s", *r.resumed_at);
    output += from;
  }
  if (checkpoints > 0) output += "; " + std::to_string(checkpoints) + " checkpoints, the last in " + checkpoint_at;
  // The process's peak resident memory: model, systems, workspace and output buffers (on
  // worker processes, theirs are their own).
  if (const double peak = memory_use().peak_bytes; peak > 0.0) {
    char mem[96];
    // Per body only where the bodies, not the program, take most of it.
    if (m.bodies.size() >= 1000)
      std::snprintf(mem, sizeof mem, "; peak memory %s (%.0f B per body)", human_bytes(peak).c_str(),
                    peak / static_cast<double>(m.bodies.size()));
    else
      std::snprintf(mem, sizeof mem, "; peak memory %s", human_bytes(peak).c_str());
    output += mem;
  }
  std::fprintf(stderr, "mbsflow: done: %ld steps (%ld rejected), %ld evaluations%s, %.3f s wall, %.3g body-steps/s%s\n",
               r.steps, r.rejected, r.evaluations, newton.c_str(), r.wall_seconds,
               body_steps / std::max(r.wall_seconds, 1e-9), output.c_str());
  return 0;
}

void add_run_options(CLI::App* sub, RunArgs& a);

// The arguments a checkpoint keeps, read as the run read them.
RunArgs parse_run_arguments(const std::vector<std::string>& arguments) {
  CLI::App app;
  RunArgs a;
  add_run_options(app.add_subcommand("run"), a);
  std::vector<std::string> args{"run"};
  args.insert(args.end(), arguments.begin(), arguments.end());
  std::reverse(args.begin(), args.end());  // CLI11 takes them last first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    throw InputError(std::string("the checkpoint's arguments do not parse: ") + e.what());
  }
  return a;
}

// mbsflow run --resume CHECKPOINT: the run again with the arguments, folder and model
// text the checkpoint keeps, from its state.
int resume(const RunArgs& given, const CLI::App& sub) {
  for (const CLI::Option* opt : sub.get_options())
    if (opt->count() > 0 && !opt->check_name("--resume") && !opt->check_name("--quiet"))
      throw InputError("--resume: the run goes on with the options it was started with; give no " + opt->get_name() +
                       " (only -q)");
  const std::string path = std::filesystem::absolute(given.resume).string();
  const CheckpointFile c = read_checkpoint_file(path);
  RunArgs a = parse_run_arguments(c.arguments);
  a.quiet = a.quiet || given.quiet;
  std::error_code ec;
  std::filesystem::current_path(c.directory, ec);
  if (ec) throw InputError("--resume: cannot go to the folder the run was started in, " + c.directory + ": " + ec.message());
  return run(a, &c, path);
}

}  // namespace

Action add_run(CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* sub = app.add_subcommand("run", "Simulate a model file and write its results");
  add_run_options(sub, *a);
  sub->add_option("--resume", a->resume,
                  "Go on with the run a checkpoint was taken from (--checkpoint-every), with its options and model, "
                  "from its state: the results file ends bit for bit as the uninterrupted run's");
  return [a, sub] { return a->resume.empty() ? run(*a) : resume(*a, *sub); };
}

namespace {

void add_run_options(CLI::App* sub, RunArgs& args) {
  RunArgs* a = &args;
  sub->add_option("model", a->model, "Model file (JSON, see docs/model-format.md)");
  add_run_settings(sub, args);
  sub->get_option("--output")->each([a](const std::string&) { a->output_given = true; });
}

}  // namespace

}  // namespace mbsflow::cli
