// mbsflow modes MODEL.json and mbsflow frf MODEL.json: small motions about a working point
// (static equilibrium, the initial state, or a state of a run), their natural modes and
// their frequency response (docs/modes.md).
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <complex>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>

#include "commands.hpp"
#include "mbsflow/analysis/equilibrium.hpp"
#include "mbsflow/analysis/frequency_response.hpp"
#include "mbsflow/analysis/modes.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/file_text.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/modes_file.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/io/results_file.hpp"
#include "mbsflow/words.hpp"

namespace mbsflow::cli {
namespace {

// A mode that grows: Re lambda above rounding's level. An undamped model's eigenvalues get
// real parts of about 1e-8 |lambda| either way from rounding (a steel beam's axial
// stiffness in the same matrix as its bending), which are no instability.
bool unstable(std::complex<double> lambda) { return lambda.real() > 1e-6 * std::abs(lambda); }


// Where to linearise: the static equilibrium (default), the model's initial state, or a
// snapshot of a run.
struct WorkingPoint {
  std::string model;
  bool at_initial = false;
  std::string at;  // a results file
  std::optional<double> time;
  bool quiet = false;
  bool assemble = false;
};

struct Loaded {
  std::shared_ptr<Model> model;
  std::unique_ptr<MultibodySystem> sys;
  Eigen::VectorXd state;
  std::string where;
  double t = 0.0;
  Eigen::SparseMatrix<double> jacobian;  // the equilibrium's, refilled by linearize (which makes it where empty)
};

// The model, its system and the state to linearise about.
Loaded working_point(const WorkingPoint& w) {
  if (w.model.empty()) throw InputError("give a MODEL file");
  if (!w.at.empty() && w.at_initial) throw InputError("--at and --at-initial: give one of them");
  if (w.time && w.at.empty()) throw InputError("--time: only with --at RESULTS.h5");
  Loaded out;
  const FileText text(w.model, "model file", max_model_bytes);
  out.model = std::make_shared<Model>(read_model_text(text.text(), w.model));
  if (w.assemble) out.model->simulation.assemble = true;
  out.sys = std::make_unique<MultibodySystem>(out.model, static_cast<int>(out.model->bodies.size()));
  out.t = out.model->simulation.t_start;
  try {
    out.state = out.sys->initial_state();
  } catch (const ModelError& e) {
    throw InputError(w.model + ": " + e.text());
  }
  if (!w.at.empty()) {
    const ResultsFile r(w.at);
    if (r.ode() || r.modes()) throw InputError(w.at + ": not the results of mbsflow run");
    const std::vector<double> times = r.time();
    if (times.empty()) throw InputError(w.at + ": no snapshots");
    const double want = w.time.value_or(times.back());
    std::size_t row = 0;
    for (std::size_t i = 0; i < times.size(); ++i)
      if (std::abs(times[i] - want) < std::abs(times[row] - want)) row = i;
    if (r.body_names().size() != out.model->bodies.size())
      throw InputError(w.at + ": its bodies are not the model's (" + std::to_string(r.body_names().size()) + " against " +
                       std::to_string(out.model->bodies.size()) + ")");
    const StateLayout& l = out.sys->layout();
    const char* series[] = {"/bodies/position", "/bodies/orientation", "/bodies/velocity", "/bodies/angular_velocity"};
    for (int s = 0; s < 4; ++s) {
      if (!r.has(series[s])) throw InputError(w.at + ": no " + series[s] + " (run with --fields position,orientation,velocity,angular_velocity)");
      const std::vector<double> v = r.read_row(series[s], row);
      const int width = s == 1 ? 4 : 3;
      for (Eigen::Index b = 0; b < l.bodies; ++b)
        for (int i = 0; i < width; ++i) {
          const Eigen::Index at = s == 0 ? l.position(b) : s == 1 ? l.orientation(b) : s == 2 ? l.velocity(b) : l.angular_velocity(b);
          out.state[at + i] = v[static_cast<std::size_t>(width * b + i)];
        }
    }
    out.t = times[row];
    char buf[64];
    std::snprintf(buf, sizeof buf, "t = %.6g s of ", out.t);
    out.where = buf + w.at;
    return out;
  }
  if (w.at_initial) {
    out.where = "initial state";
    return out;
  }
  EquilibriumOptions eo;
  const auto start = std::chrono::steady_clock::now();
  const bool terminal = !w.quiet && ::isatty(2);
  if (terminal)
    eo.progress = [](int iteration, double residual) {
      std::fprintf(stderr, "\rmbsflow: static equilibrium: iteration %d, residual %.3g N or N m   ", iteration, residual);
    };
  Equilibrium e = find_equilibrium(*out.sys, out.t, out.state, eo);
  if (terminal) std::fprintf(stderr, "\r%80s\r", "");
  out.state = e.state;
  out.jacobian.swap(e.jacobian);  // Eigen 3.4's SparseMatrix has no move: a "move" copies
  out.where = "static equilibrium";
  if (!w.quiet)
    std::fprintf(stderr, "mbsflow: static equilibrium in %s (%.3g s): residual %.3g N or N m, from %.3g at the start\n",
                 count_of(e.iterations, "iteration").c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), e.residual,
                 e.initial_residual);
  return out;
}

void add_working_point(CLI::App* sub, WorkingPoint& w) {
  sub->add_option("model", w.model, "Model file (JSON, docs/model-format.md)")->required();
  sub->add_flag("--at-initial", w.at_initial, "Linearise at the model's initial state, not at its static equilibrium");
  sub->add_option("--at", w.at, "Linearise at a snapshot of this run's results file (mbsflow run -o), e.g. a steadily "
                                "turning mechanism");
  sub->add_option("--time", w.time, "With --at: the snapshot nearest this time (default: the last)");
  sub->add_flag("--assemble", w.assemble, "Move the bodies onto rigid joints that their initial positions violate");
  sub->add_flag("-q,--quiet", w.quiet, "Print only warnings, errors and the results");
}

// The direction (x y z rx ry rz, world frame) that holds most of a mode's kinetic energy,
// summed over the bodies: "z 97 %" for a bounce, "ry 80 %" for a pitch; "elastic" for the
// flexible bodies' modal coordinates.
std::string main_direction(const LinearModel& lm, const Eigen::VectorXcd& x) {
  const Eigen::VectorXcd mx = lm.M * x;
  double per[7] = {}, total = 0.0;
  for (std::size_t k = 0; k < lm.coords.bodies.size(); ++k)
    for (Eigen::Index i = lm.coords.start[k]; i < lm.coords.start[k + 1]; ++i) {
      const double e = (std::conj(x[i]) * mx[i]).real();
      per[std::min<Eigen::Index>(i - lm.coords.start[k], 6)] += e;
      total += e;
    }
  int best = 0;
  for (int d = 1; d < 7; ++d)
    if (per[d] > per[best]) best = d;
  const char* names[] = {"x", "y", "z", "rx", "ry", "rz", "elastic"};
  char buf[32];
  std::snprintf(buf, sizeof buf, "%s %.0f %%", names[best], total > 0.0 ? 100.0 * per[best] / total : 0.0);
  return buf;
}

struct ModesArgs {
  WorkingPoint at;
  int count = 10;
  bool undamped = false;
  std::string solver = "auto";
  std::string output;
  bool output_given = false, force = false;
};

// The equilibrium's iterations and the eigensolver allocate and free arrays of hundreds of
// MB again and again (triplets, K, D, the augmented matrix, KLU's factors). Above glibc's
// mmap limit (32 MB) each is mapped afresh and its pages zeroed by the kernel: 36 % of a
// 100 000-link equilibrium's time. This process keeps freed memory in its heap instead
// (equilibrium 83 s -> 68 s there; the same peak memory).
void keep_freed_memory() {
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
  mallopt(M_TOP_PAD, 1 << 30);
}

int modes(const ModesArgs& a) {
  keep_freed_memory();
  if (a.output_given || !a.output.empty()) check_output_path(a.output, {{a.at.model, a.at.at}, a.force});
  Loaded w = working_point(a.at);
  const auto start = std::chrono::steady_clock::now();
  const LinearModel lm = linearize(*w.sys, w.t, w.state, &w.jacobian);
  Eigen::SparseMatrix<double>().swap(w.jacobian);  // its 600 MB (100 000 bodies) free for the eigensolver
  ModeOptions o;
  o.count = a.count;
  o.damped = !a.undamped;
  o.solver = a.solver == "dense" ? ModeSolver::dense : a.solver == "sparse" ? ModeSolver::sparse : ModeSolver::automatic;
  if (!a.at.quiet) o.notice = [](const std::string& what) { std::fprintf(stderr, "mbsflow: %s\n", what.c_str()); };
  const Modes m = compute_modes(lm, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Model& model = *w.model;
  std::printf("model %s: %s, linearised at the %s: %s (%ld coordinates less %ld joint rows), %s\n", model.name.c_str(),
              count_of(static_cast<long long>(lm.coords.bodies.size()), "free body", "free bodies").c_str(), w.where.c_str(),
              count_of(static_cast<long long>(m.free_coordinates), "degree of freedom", "degrees of freedom").c_str(),
              static_cast<long>(lm.size()), static_cast<long>(lm.C.rows()), m.solver.c_str());
  std::printf("%5s %14s %12s %26s %10s %12s  %s\n", "mode", "frequency Hz", "damping", "eigenvalue 1/s", "residual",
              "motion", "largest kinetic share");
  for (std::size_t j = 0; j < m.frequency.size(); ++j) {
    Eigen::Index body = 0;
    const double share = m.kinetic_share.col(static_cast<Eigen::Index>(j)).maxCoeff(&body);
    char lambda[64];
    std::snprintf(lambda, sizeof lambda, "%.6g %+.6gi", m.eigenvalue[j].real(), m.eigenvalue[j].imag());
    std::printf("%5zu %14.6g %12.4g %26s %10.2g %12s  %s (%.3g %%)%s\n", j + 1, m.frequency[j], m.damping_ratio[j], lambda,
                m.residual[j], main_direction(lm, m.shape.col(static_cast<Eigen::Index>(j))).c_str(), model.bodies[static_cast<std::size_t>(lm.coords.bodies[static_cast<std::size_t>(body)])].name.c_str(),
                100.0 * share, m.rigid_body[j] ? "  rigid-body motion" : unstable(m.eigenvalue[j]) ? "  unstable" : "");
  }
  if (!a.output.empty()) {
    const ModesFileWritten file = write_modes_file(a.output, lm, m, {model_to_json(model), invocation(), w.where});
    std::fprintf(stderr, "mbsflow: %s in %s (%.3f s); ParaView animates them from %s (%s)\n",
                 count_of(static_cast<long long>(m.frequency.size()), "mode").c_str(), a.output.c_str(), seconds,
                 file.xdmf.c_str(),
                 file.frames > 0 ? (std::to_string(file.frames) + " frames a period; time k + f is mode k at f of its period").c_str()
                                 : "one still picture a mode, the model being too large to animate: warp by 'shape'");
  } else if (!a.at.quiet) {
    std::fprintf(stderr, "mbsflow: %s (%.3f s); -o FILE.h5 keeps their shapes\n",
                 count_of(static_cast<long long>(m.frequency.size()), "mode").c_str(), seconds);
  }
  return 0;
}

struct FrfArgs {
  WorkingPoint at;
  std::vector<std::string> inputs, outputs;
  double from = 0.1, to = 100.0;
  int points = 200;
  bool linear = false;
  std::string output, state_space;
};

int frf(const FrfArgs& a) {
  keep_freed_memory();
  if (!a.output.empty()) check_output_path(a.output, {{a.at.model}, true});
  if (!(a.from > 0.0) || !(a.to > a.from)) throw InputError("--from and --to: 0 < from < to (Hz)");
  Loaded w = working_point(a.at);
  const Model& model = *w.model;
  std::vector<Channel> in, out;
  for (const std::string& s : a.inputs) in.push_back(parse_channel(model, s, true));
  for (const std::string& s : a.outputs) out.push_back(parse_channel(model, s, false));
  const LinearModel lm = linearize(*w.sys, w.t, w.state, &w.jacobian);
  std::vector<double> hz;
  for (int i = 0; i < a.points; ++i) {
    const double s = a.points == 1 ? 0.0 : static_cast<double>(i) / (a.points - 1);
    hz.push_back(a.linear ? a.from + s * (a.to - a.from) : a.from * std::pow(a.to / a.from, s));
  }
  const FrequencyResponse r = frequency_response(lm, in, out, hz);
  const std::string csv = a.output.empty() ? std::filesystem::path(a.at.model).stem().string() + "_frf.csv" : a.output;
  std::ofstream f(csv);
  f << "frequency_hz";
  for (const Channel& o : out)
    for (const Channel& i : in) {
      const std::string pair = channel_name(model, o, false) + "/" + channel_name(model, i, true);
      f << "," << pair << " magnitude," << pair << " phase_deg";
    }
  f << "\n";
  f.precision(10);
  for (std::size_t k = 0; k < hz.size(); ++k) {
    f << hz[k];
    for (Eigen::Index o = 0; o < r.h[k].rows(); ++o)
      for (Eigen::Index i = 0; i < r.h[k].cols(); ++i)
        f << "," << std::abs(r.h[k](o, i)) << "," << std::arg(r.h[k](o, i)) * 180.0 / std::numbers::pi;
    f << "\n";
  }
  if (!f.flush()) throw InputError("cannot write " + csv);
  std::fprintf(stderr, "mbsflow: frequency response at %s in %s (linearised at the %s)\n",
               count_of(a.points, "frequency", "frequencies").c_str(), csv.c_str(), w.where.c_str());
  if (!a.state_space.empty()) {
    const StateSpace s = state_space(lm, in, out);
    std::filesystem::create_directories(a.state_space);
    for (const auto& [name, m] : {std::pair{"A", &s.A}, {"B", &s.B}, {"C", &s.C}, {"D", &s.D}})
      write_matrix_market((std::filesystem::path(a.state_space) / (std::string(name) + ".mtx")).string(), *m);
    std::fprintf(stderr, "mbsflow: state-space model A (%ld x %ld), B, C, D in %s/*.mtx (Matrix Market)\n",
                 static_cast<long>(s.A.rows()), static_cast<long>(s.A.cols()), a.state_space.c_str());
  }
  return 0;
}

}  // namespace

Action add_modes(CLI::App& app) {
  auto a = std::make_shared<ModesArgs>();
  CLI::App* sub = app.add_subcommand("modes", "Natural frequencies, damping and mode shapes about the static equilibrium "
                                              "(or a given state): docs/modes.md");
  add_working_point(sub, a->at);
  sub->add_option("-n,--count", a->count, "The lowest modes to find (all there are where fewer)")
      ->check(CLI::Range(1, 100000))->capture_default_str();
  sub->add_flag("--undamped", a->undamped, "Modes of M and K only (real shapes), not the damped complex ones");
  sub->add_option("--solver", a->solver, "auto (dense up to 200 free coordinates or where -n asks for a quarter of them, else sparse), dense, or sparse "
                                         "(shift-invert on a KLU factorisation: Arnoldi, Spectra's where it does not "
                                         "converge, or Spectra's Lanczos for --undamped)")
      ->check(CLI::IsMember({"auto", "dense", "sparse"}))->capture_default_str();
  sub->add_option("-o,--output", a->output, "HDF5 file for the modes, their shapes and the working point")
      ->each([a](const std::string&) { a->output_given = true; });
  sub->add_flag("--force", a->force, "With -o: replace the file there even if it is not an mbsflow results file");
  return [a] { return modes(*a); };
}

Action add_frf(CLI::App& app) {
  auto a = std::make_shared<FrfArgs>();
  CLI::App* sub = app.add_subcommand("frf", "Frequency response of the linearised model: harmonic forces in, motions out, "
                                            "as magnitude and phase (CSV) and a state-space model: docs/modes.md");
  add_working_point(sub, a->at);
  sub->add_option("--input", a->inputs, "BODY:fx|fy|fz|tx|ty|tz, a harmonic force or torque of unit amplitude (world "
                                        "frame); several allowed")->required();
  sub->add_option("--output", a->outputs, "BODY:x|y|z|rx|ry|rz, or vx.. for velocity, ax.. for acceleration; several "
                                          "allowed")->required();
  sub->add_option("--from", a->from, "Lowest frequency, Hz")->capture_default_str();
  sub->add_option("--to", a->to, "Highest frequency, Hz")->capture_default_str();
  sub->add_option("--points", a->points, "Frequencies, spaced logarithmically")->check(CLI::Range(1, 1000000))->capture_default_str();
  sub->add_flag("--linear", a->linear, "Space the frequencies evenly instead");
  sub->add_option("-o,--csv", a->output, "CSV to write (default: MODEL_frf.csv)");
  sub->add_option("--state-space", a->state_space, "Folder to write A, B, C, D (Matrix Market) of z' = A z + B u, y = C z + D u");
  return [a] { return frf(*a); };
}

}  // namespace mbsflow::cli
