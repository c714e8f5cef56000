// mbsflow command line. Exit codes: 0 done, 1 the run failed, 2 bad input or usage.
#include <algorithm>
#include <iostream>
#include <vector>

#include "commands.hpp"
#include "huge_pages.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/version.hpp"

int main(int argc, char** argv) {
  mbsflow::cli::restart_with_huge_pages(argv);
  CLI::App app{"mbsflow: multibody dynamics and large ODE systems, in parallel"};
  app.set_version_flag("--version", MBSFLOW_VERSION);
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, mbsflow::cli::Action>> commands;
  auto add = [&](auto adder) {
    const std::size_t before = app.get_subcommands({}).size();
    mbsflow::cli::Action action = adder(app);
    commands.emplace_back(app.get_subcommands({})[before], std::move(action));
  };
  add(mbsflow::cli::add_run);
  add(mbsflow::cli::add_generate);
  add(mbsflow::cli::add_partition);
  add(mbsflow::cli::add_plan);
  add(mbsflow::cli::add_info);
  add(mbsflow::cli::add_export);
  add(mbsflow::cli::add_plot);
  add(mbsflow::cli::add_view);
  add(mbsflow::cli::add_bench);
  add(mbsflow::cli::add_worker);
  add(mbsflow::cli::add_ode);
  add(mbsflow::cli::add_modes);
  add(mbsflow::cli::add_frf);
  add(mbsflow::cli::add_reduce);
  add(mbsflow::cli::add_keygen);
  mbsflow::cli::set_invocation(argc, argv);
  // A mistyped command is named, with the commands there are (CLI11 would say only that a
  // subcommand is required).
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const auto& [sub, action] : commands) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr << "mbsflow: unknown command '" << argv[1] << "'" << mbsflow::cli::closest_name(argv[1], commands)
                << "; the commands are " << names << " (mbsflow --help)\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    for (auto& [sub, action] : commands)
      if (sub->parsed()) return action();
  } catch (const mbsflow::InputError& e) {
    std::cerr << mbsflow::render(e.text(), mbsflow::cli::flag_for) << '\n';
    return 2;
  } catch (const mbsflow::RunError& e) {
    std::cerr << "mbsflow: " << mbsflow::render(e.text(), mbsflow::cli::flag_for) << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "mbsflow: internal error: " << e.what() << '\n';
    return 1;
  }
  return 2;
}

namespace mbsflow::cli {
namespace {
std::string command_line;
std::vector<std::string> arguments;
}  // namespace
const std::string& invocation() { return command_line; }
const std::vector<std::string>& invocation_arguments() { return arguments; }
std::string closest_name(const std::string& given,
                         const std::vector<std::pair<CLI::App*, Action>>& commands) {
  // Levenshtein distance; a name within two edits of the given one is suggested.
  auto distance = [](const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    return row[b.size()];
  };
  std::string best;
  std::size_t best_distance = 3;
  for (const auto& c : commands) {
    const std::size_t d = distance(given, c.first->get_name());
    if (d < best_distance) {
      best_distance = d;
      best = c.first->get_name();
    }
  }
  return best.empty() ? "" : " (did you mean " + best + "?)";
}

void set_invocation(int argc, char** argv) {
  command_line.clear();
  arguments.assign(argv, argv + argc);
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
}
}  // namespace mbsflow::cli
