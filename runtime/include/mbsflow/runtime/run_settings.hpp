#pragma once
// Every setting of a run, declared once: its name, type, default, range and help. The
// CLI's flags (mbsflow run), Python's keywords (mbsflow.run, mbsflow.Simulation), the fields of a model's
// simulation block, the names that messages give as {name} and docs/run-settings.md's
// table are all read from run_settings(); a setting is added there and in RunRequest.
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace mbsflow {

// What a front end asks of a run, in its users' terms; unset optionals and the defaults
// here leave the choice to the model and to run_request.hpp's rules.
struct RunRequest {
  // The model's simulation block, replaced where given.
  std::optional<double> t_start, t_end, step, rtol, atol, output_interval;
  std::optional<int> output_every;  // replaces an output interval too
  std::optional<std::string> method, variant;
  bool assemble = false;
  // The implicit methods' linear algebra.
  std::string linear_solver = "auto", jacobian = "auto";
  // Results.
  std::string output;
  bool force = false;
  std::string fields = "position,orientation,velocity,angular_velocity,energy";
  bool quiet = false, timings = false;
  // Threads and submodels.
  int threads = 0;
  std::optional<int> partitions;
  std::string executor = "flow", partition_file, partitioner = "best";
  // Worker processes.
  std::string cluster;
  int processes = 0;
  std::string transport = "tcp";
  bool slurm = false;
  int slurm_port = 0;
  std::string slurm_key;
  bool insecure = false, insecure_network = false;
  double exchange_delay = 0.0;
  // Loose coupling.
  std::string coupling = "tight";
  std::optional<double> macro_step, coupling_tol, overlap;
  int extrapolation = 1, max_lag = 0;
  bool exact_lag = false;
  std::string submodel_methods;  // comma-separated, one per submodel
  // Checkpoints.
  double checkpoint_every = 0.0;
  std::string checkpoint;
};

// Where a setting can be given; in_simulation: a keyword of mbsflow.Simulation too (a model
// stepped by the program), under its Python name.
enum SettingPlace : unsigned { in_cli = 1, in_python = 2, in_model = 4, in_simulation = 8 };

struct RunSetting {
  using Field = std::variant<std::optional<double> RunRequest::*, double RunRequest::*, std::optional<int> RunRequest::*,
                             int RunRequest::*, std::optional<std::string> RunRequest::*, std::string RunRequest::*,
                             bool RunRequest::*>;
  const char* name;  // in messages ({name}), the model's simulation block and Python
  const char* flag;  // the CLI's ("-o,--output"); "" where not on the command line
  unsigned places;   // SettingPlace bits
  Field field;
  const char* help;  // with {other} for another setting's name in the reader's terms
  // Numbers: the range (lo excluded where lo_open); text: the choices (a comma-separated
  // list where `list`), from `choices` or, where that is empty, choices_of().
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  std::vector<std::string> choices = {};
  std::vector<std::string> (*choices_of)() = nullptr;
  bool list = false;
  const char* needs = "";     // another setting's name: only with it
  const char* excludes = "";  // another setting's name: not with it
  const char* python_name = nullptr;  // where Python's keyword differs from `name`
  const char* library_name = nullptr;  // the option's name where the library's messages give another

  const char* keyword() const { return python_name ? python_name : name; }
  std::string long_flag() const;      // "--output"
  std::vector<std::string> allowed() const;
  bool optional() const;              // no value unless given
  bool is_flag() const;               // on or off
  bool is_integer() const;
  bool is_number() const;             // integer or real
};

const std::vector<RunSetting>& run_settings();
// The setting of that name (or library_name), or null.
const RunSetting* find_run_setting(std::string_view name);

// Sets s's field of `request` from `read`, which a front end gives for its values: flag()
// (a bool), number() and text(); the number or text is checked against s's range or choices
// and read.fail(what is wrong) called (it must throw) where it breaks them.
template <class Read>
void set_setting(const RunSetting& s, RunRequest& request, Read&& read);

// The items of a comma-separated list ("rk4,dopri5", a list setting's value, `excludes`);
// none for empty text.
std::vector<std::string> comma_items(std::string_view list);

// What is wrong with a value of `s` (a number, or text for text settings), in the reader's
// terms ("must be > 0", "unknown method (rk4, ...)"); empty where nothing is.
std::string setting_error(const RunSetting& s, double value);
std::string setting_error(const RunSetting& s, const std::string& value);

// The default of `s` as a user would write it; empty where it has none (chosen at the run).
std::string default_text(const RunSetting& s);

// docs/run-settings.md's table: a row per setting with its flag, keyword, model field,
// default, range and help.
std::string run_settings_table();

template <class Read>
void set_setting(const RunSetting& s, RunRequest& request, Read&& read) {
  std::visit(
      [&](auto member) {
        auto& field = request.*member;
        using F = std::decay_t<decltype(field)>;
        if constexpr (std::is_same_v<F, bool>) {
          field = read.flag();
        } else if constexpr (std::is_same_v<F, std::string> || std::is_same_v<F, std::optional<std::string>>) {
          std::string text = read.text();
          if (const std::string e = setting_error(s, text); !e.empty()) read.fail(e);
          field = std::move(text);
        } else {
          const double x = read.number();
          if (const std::string e = setting_error(s, x); !e.empty()) read.fail(e);
          if constexpr (std::is_same_v<F, int> || std::is_same_v<F, std::optional<int>>)
            field = static_cast<int>(x);
          else
            field = x;
        }
      },
      s.field);
}

}  // namespace mbsflow
