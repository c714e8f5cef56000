// mbsflow info FILE.h5: what a results file holds.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "mbsflow/io/results_file.hpp"

namespace mbsflow::cli {
namespace {

std::string shape_text(const std::vector<std::uint64_t>& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) out += (i ? " x " : "") + std::to_string(s[i]);
  return out;
}

int info(const std::string& path) {
  const ResultsFile r(path);
  const std::vector<double> t = r.time();
  auto text = [&](const char* name) { return r.string_attribute(name).value_or("?"); };
  auto number = [&](const char* name) { return r.number_attribute(name).value_or(std::nan("")); };
  std::printf("file          %s (%ju bytes)\n", path.c_str(), r.size_bytes());
  const std::size_t joints = r.joint_names().size();
  std::printf("model         %s: %zu bodies%s\n", text("model_name").c_str(), r.body_names().size(),
              joints ? (", " + std::to_string(joints) + " joints with forces").c_str() : "");
  std::printf("method        %s, step %.6g s, output every %g\n", text("method").c_str(), number("step"),
              number("output_every"));
  std::printf("run           t = %.6g .. %.6g s requested\n", number("t_start"), number("t_end"));
  if (t.empty())
    std::printf("snapshots     none\n");
  else
    std::printf("snapshots     %zu, t = %.6g .. %.6g s%s\n", t.size(), t.front(), t.back(),
                t.back() < number("t_end") ? " (run ended early)" : "");
  std::printf("fields        %s\n", text("fields").c_str());
  for (const BodyField& f : body_fields)
    if (r.has(f.dataset)) std::printf("  %-24s %s\n", f.dataset, shape_text(r.shape(f.dataset)).c_str());
  for (const char* d : {energy_dataset, joint_force_dataset, motor_effort_dataset})
    if (r.has(d)) std::printf("  %-24s %s\n", d, shape_text(r.shape(d)).c_str());
  std::printf("written by    mbsflow %s\n", text("mbsflow_version").c_str());
  std::printf("command line  %s\n", text("command_line").c_str());
  return 0;
}

}  // namespace

Action add_info(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand("info", "Print what a results file holds: settings, sizes, time span");
  sub->add_option("file", *path, "Results file (.h5)")->required();
  return [path] { return info(*path); };
}

}  // namespace mbsflow::cli
