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
  add(mbsflow::cli::add_keygen);
  mbsflow::cli::set_invocation(argc, argv);
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
std::string flag_for(const std::string& setting, const std::string* value) {
  std::string flag = setting == "methods" ? "submodel-methods" : setting;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return "--" + flag + (value ? " " + *value : "");
}
void set_invocation(int argc, char** argv) {
  command_line.clear();
  arguments.assign(argv, argv + argc);
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
}
}  // namespace mbsflow::cli
