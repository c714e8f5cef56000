// mbsflow export FILE.h5 --csv DIR [--bodies a,b]: results as CSV, one file per body.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mbsflow/io/results_file.hpp"

namespace mbsflow::cli {
namespace {

struct ExportArgs {
  std::string file, csv;
  std::vector<std::string> bodies;
};

int export_results(const ExportArgs& a) {
  const ResultsFile r(a.file);
  const std::vector<std::string> files = export_csv(r, a.csv, a.bodies);
  std::fprintf(stderr, "mbsflow: wrote %zu CSV file%s to %s\n", files.size(), files.size() == 1 ? "" : "s", a.csv.c_str());
  return 0;
}

}  // namespace

Action add_export(CLI::App& app) {
  auto a = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export", "Write results as CSV: one file per body with a header row (a modes file: modes.csv and each body's part of every mode)");
  sub->add_option("file", a->file, "Results file (.h5)")->required();
  sub->add_option("--csv", a->csv, "Folder for the CSV files (created if missing)")->required();
  sub->add_option("--bodies", a->bodies, "Bodies to export, comma-separated or one per option (default: all)")->delimiter(',');
  return [a] { return export_results(*a); };
}

}  // namespace mbsflow::cli
