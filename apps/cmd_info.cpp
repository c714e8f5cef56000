// mbsflow info FILE.h5: what a results file holds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "mbsflow/io/reduced_part_file.hpp"
#include "mbsflow/io/results_file.hpp"
#include "mbsflow/words.hpp"

namespace mbsflow::cli {
namespace {

std::string shape_text(const std::vector<std::uint64_t>& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) out += (i ? " x " : "") + std::to_string(s[i]);
  return out;
}

// The results of mbsflow ode: problem, method, solution points and the steps tried.
std::string unit_of(const ResultsFile& r, const char* dataset) {
  return r.dataset_string_attribute(dataset, "units").value_or("?");
}

int info_ode(const ResultsFile& r) {
  const std::vector<double> t = r.time();
  auto text = [&](const char* name) { return r.string_attribute(name).value_or("?"); };
  auto number = [&](const char* name) { return r.number_attribute(name).value_or(std::nan("")); };
  std::printf("file          %s (%ju bytes)\n", r.path().c_str(), r.size_bytes());
  std::printf("problem       %s: %.0f equations (mbsflow ode)\n", text("problem").c_str(), number("n"));
  const std::string tableau = r.string_attribute("tableau").value_or("");
  std::printf("method        %s%s%s, %s iteration, order %.0f, tol %g\n", text("method").c_str(), tableau.empty() ? "" : " ",
              tableau.c_str(), text("iteration").c_str(), number("order"), number("tol"));
  if (t.empty())
    std::printf("solution      no points\n");
  else
    std::printf("solution      %zu points, t = %.6g .. %.6g, components kept %ju\n", t.size(), t.front(), t.back(),
                r.shape("/solution/values").back());
  if (r.has("/solution/error")) std::printf("max error     %.3e (against the exact solution)\n", number("max_error"));
  const std::vector<double> taken = r.read("/steps/taken");
  const auto rejected = std::count(taken.begin(), taken.end(), 0.0);
  std::printf("steps         %zu tried, %td rejected, %.0f rhs evaluations, %.3f s wall\n", taken.size(), rejected,
              number("rhs_evaluations"), number("wall_seconds"));
  std::printf("datasets      /solution/{time,components,values%s}, /steps/{t,tau,taken,error,...}\n",
              r.has("/solution/error") ? ",error" : "");
  std::printf("written by    mbsflow %s\n", text("mbsflow_version").c_str());
  std::printf("command line  %s\n", text("command").c_str());
  return 0;
}

// The results of mbsflow modes: where the model was linearised, and its modes.
int info_modes(const ResultsFile& r) {
  auto text = [&](const char* name) { return r.string_attribute(name).value_or("?"); };
  const std::vector<double> f = r.read("/modes/frequency"), zeta = r.read("/modes/damping_ratio"), rigid = r.read("/modes/rigid_body");
  std::printf("file          %s (%ju bytes)\n", r.path().c_str(), r.size_bytes());
  std::printf("model         %s: %s\n", text("model_name").c_str(),
              count_of(static_cast<long long>(r.body_names().size()), "body", "bodies").c_str());
  std::printf("modes         %s about the %s, %s\n", count_of(static_cast<long long>(f.size()), "mode").c_str(),
              text("linearised_at").c_str(), text("solver").c_str());
  for (std::size_t j = 0; j < f.size(); ++j)
    std::printf("  %4zu  %12.6g Hz  damping ratio %.4g%s\n", j + 1, f[j], zeta[j] == 0.0 ? 0.0 : zeta[j],
                rigid[j] != 0.0 ? "  (rigid-body motion)" : "");
  std::printf("written by    mbsflow %s\n", text("mbsflow_version").c_str());
  std::printf("command line  %s\n", text("command_line").c_str());
  return 0;
}

// A part that mbsflow reduce wrote: its coordinates, modes, mass and free frequencies.
int info_part(const std::string& path) {
  ReducedPartInfo made;
  const ReducedPart p = read_reduced_part(path, &made);
  std::printf("file          %s: a reduced finite-element part (Craig-Bampton)\n", path.c_str());
  std::printf("from          %s\n", made.source.c_str());
  std::printf("coordinates   %td: %s and %s\n", p.mass.rows(), count_of(static_cast<long long>(p.interface_dofs.size()), "interface DOF").c_str(),
              count_of(p.modes, "fixed-interface mode").c_str());
  for (Eigen::Index j = 0; j < p.fixed_frequency.size(); ++j) std::printf("  %4td  %12.6g Hz\n", j + 1, p.fixed_frequency[j]);
  const MassProperties& m = p.properties;
  std::printf("mass          %.6g kg, centre (%.6g, %.6g, %.6g) m\n", m.mass, m.centre.x(), m.centre.y(), m.centre.z());
  std::printf("inertia       [%.6g %.6g %.6g; %.6g %.6g %.6g; %.6g %.6g %.6g] kg m^2 about the centre\n", m.inertia(0, 0), m.inertia(0, 1),
              m.inertia(0, 2), m.inertia(1, 0), m.inertia(1, 1), m.inertia(1, 2), m.inertia(2, 0), m.inertia(2, 1), m.inertia(2, 2));
  std::printf("free          %s\n", free_frequencies_text(p).c_str());
  std::printf("command line  %s\n", made.command_line.c_str());
  return 0;
}

int info(const std::string& path) {
  if (is_reduced_part(path)) return info_part(path);
  const ResultsFile r(path);
  if (r.ode()) return info_ode(r);
  if (r.modes()) return info_modes(r);
  const std::vector<double> t = r.time();
  auto text = [&](const char* name) { return r.string_attribute(name).value_or("?"); };
  auto number = [&](const char* name) { return r.number_attribute(name).value_or(std::nan("")); };
  std::printf("file          %s (%ju bytes)\n", path.c_str(), r.size_bytes());
  const std::size_t joints = r.has(joint_force_dataset) ? r.joint_names().size() : 0;
  std::printf("model         %s: %s%s\n", text("model_name").c_str(),
              count_of(static_cast<long long>(r.body_names().size()), "body", "bodies").c_str(),
              joints ? (", " + count_of(static_cast<long long>(joints), "joint") + " with forces").c_str() : "");
  std::printf("method        %s, step %.6g s, output every %g\n", text("method").c_str(), number("step"),
              number("output_every"));
  if (r.has("/coupling/t_end")) {  // a loosely coupled run: its macro steps and coupling errors
    const std::vector<double> start = r.read("/coupling/t_start"), end = r.read("/coupling/t_end");
    const std::vector<double> error = r.read("/coupling/position_error");
    double shortest = INFINITY, longest = 0.0, worst = 0.0;
    for (std::size_t i = 0; i < end.size() && i < start.size(); ++i) {
      shortest = std::min(shortest, end[i] - start[i]);
      longest = std::max(longest, end[i] - start[i]);
    }
    for (double e : error) worst = std::max(worst, e);
    std::printf("coupling      loose: %s of %.4g .. %.4g s, coupling error at most %.3g m\n",
                count_of(static_cast<long long>(end.size()), "macro step").c_str(), end.empty() ? 0.0 : shortest, longest, worst);
  }
  std::printf("run           t = %.6g .. %.6g s requested\n", number("t_start"), number("t_end"));
  if (t.empty())
    std::printf("snapshots     none\n");
  else
    std::printf("snapshots     %zu, t = %.6g .. %.6g s%s\n", t.size(), t.front(), t.back(),
                t.back() < number("t_end") ? " (run ended early)" : "");
  std::printf("fields        %s\n", text("fields").c_str());
  auto dataset = [&](const char* d) {
    if (r.has(d)) std::printf("  %-24s %-16s [%s]\n", d, shape_text(r.shape(d)).c_str(), unit_of(r, d).c_str());
  };
  for (const BodyField& f : body_fields) dataset(f.dataset);
  for (const char* d : {body_energy_dataset, energy_dataset, joint_force_dataset, motor_effort_dataset, joint_attachment_dataset})
    dataset(d);
  std::printf("written by    mbsflow %s\n", text("mbsflow_version").c_str());
  std::printf("command line  %s\n", text("command_line").c_str());
  return 0;
}

}  // namespace

Action add_info(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand("info", "Print what a results file (or a reduced part) holds: settings, sizes, time span");
  sub->add_option("file", *path, "Results file (.h5) of run, ode or modes, or a part of mbsflow reduce")->required();
  return [path] { return info(*path); };
}

}  // namespace mbsflow::cli
