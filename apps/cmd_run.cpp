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
#include "run_report.hpp"
#include "mbsflow/runtime/stop_signals.hpp"

namespace mbsflow::cli {
namespace {

// The settings (mbsflow/runtime/run_settings.hpp) with the model file and --resume.
struct RunArgs : RunRequest {
  std::string model;
  bool output_given = false;  // -o "" is refused, not taken as no -o
  std::string resume;         // a checkpoint file to go on from
};

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

// A run's checkpoints: the file holds the arguments, folder and model text with the run's
// state, every --checkpoint-every s; a resumed run goes on from its checkpoint's state.
struct RunCheckpoints {
  Checkpointing checkpointing;
  CheckpointFile file;
  long written = 0;
  std::string path;

  // What RunOptions::checkpoint takes: null where the run neither writes nor resumes one.
  Checkpointing* set_up(const RunArgs& a, std::string model_text, const CheckpointFile* resumed,
                        const std::string& resumed_path) {
    if (a.checkpoint_every > 0.0) {
      path = checkpoint_path(a);
      file.arguments = resumed ? resumed->arguments : run_arguments();
      file.directory = resumed ? resumed->directory : std::filesystem::current_path().string();
      file.model_text = std::move(model_text);
      checkpointing.every_s = a.checkpoint_every;
      checkpointing.write = [this](std::vector<std::uint8_t>&& state) {
        file.state = std::move(state);
        write_checkpoint_file(path, file);
        ++written;
      };
    }
    if (resumed) {
      checkpointing.resume = resumed->state;
      checkpointing.resume_from = "checkpoint " + resumed_path;
      if (!a.quiet) std::fprintf(stderr, "mbsflow: going on from checkpoint %s\n", resumed_path.c_str());
    }
    return checkpointing.write || resumed ? &checkpointing : nullptr;
  }
};

// The worker processes of a cluster file or of a Slurm step's other tasks (none: empty).
ClusterConfig cluster_of(const RunArgs& a, const std::optional<SlurmLaunch>& slurm) {
  ClusterConfig cc;
  if (!a.cluster.empty()) {
    cc = read_cluster_file(a.cluster);
    cc.insecure = a.insecure_network ? Insecure::anywhere : a.insecure ? Insecure::loopback : Insecure::no;
    check_cluster_security(cc);  // before the run is set up
  }
  if (slurm && slurm->step.tasks() > 1) {
    cc = slurm_cluster(slurm->step, slurm->base_port, slurm->keys);
    check_cluster_security(cc);
  } else if (slurm && !a.quiet) {
    std::fprintf(stderr, "mbsflow: --slurm with one task: a run on this process's threads\n");
  }
  return cc;
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
  const ClusterCoupling coupling{loose ? &lo : nullptr, a.exchange_delay};
  if (cluster) check_cluster_run(m, o, coupling);  // before any worker is started
  std::optional<LocalWorkers> local;
  ClusterConfig cc = cluster_of(a, slurm);
  // Loose coupling cuts the model even into one submodel (then it is a plain run).
  // Local workers take a submodel each; the model is cut before they are started, so that a
  // model that cannot be cut so far is refused before any process exists.
  const int default_k = a.processes > 0 ? a.processes
                        : cluster       ? cluster_submodels(cc)
                                        : default_submodels(m, o.method, loose, threads);
  std::optional<Decomposition> d;
  try {
    d = cut_of_request(m, a, default_k, !cluster && !loose);
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
  say_cut(m, a, o, d, cluster ? &cc : nullptr, settled.loose, threads);
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
  RunCheckpoints checkpoints;
  o.checkpoint = checkpoints.set_up(a, std::move(model_text), resumed, resumed_path);
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
  say_done(m, r, sink.get(), a.output, checkpoints.written, checkpoints.path);
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
  if (!a.output.empty()) mend_results_file_to_resume(a.output);  // before check_output_path() reads it
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
