// The run's settings, declared once (run_settings.hpp): names, ranges, defaults and the
// reference table in docs/run-settings.md.
#include <catch2/catch.hpp>
#include <fstream>
#include <set>
#include <sstream>

#include "mbsflow/runtime/run_request.hpp"
#include "mbsflow/runtime/run_settings.hpp"

using namespace mbsflow;

TEST_CASE("run settings: each declared once, with its default in its range", "[settings]") {
  std::set<std::string> names, keywords, flags;
  for (const RunSetting& s : run_settings()) {
    INFO(s.name);
    CHECK(names.insert(s.name).second);
    CHECK(s.places != 0);
    if (s.places & in_python) CHECK(keywords.insert(s.keyword()).second);
    CHECK(((s.places & in_cli) != 0) == (*s.flag != 0));
    if (*s.flag) CHECK(flags.insert(s.long_flag()).second);
    const std::string help = s.help;
    CHECK(!help.empty());
    CHECK(help.back() != '.');  // the table and the CLI add their own
    if (*s.needs) CHECK(find_run_setting(s.needs));
    // A default is in range, or stands for "none" (empty text).
    const std::string d = default_text(s);
    if (s.is_number() && !d.empty()) CHECK(setting_error(s, std::stod(d)).empty());
    if (!s.allowed().empty() && !d.empty()) CHECK(setting_error(s, d).empty());
  }
  CHECK(find_run_setting("nonsense") == nullptr);
}

TEST_CASE("run settings: values out of range or not among the choices are named", "[settings]") {
  CHECK(setting_error(*find_run_setting("step"), 0.0) == "must be > 0");
  CHECK(setting_error(*find_run_setting("step"), 1e-3).empty());
  CHECK(setting_error(*find_run_setting("extrapolation"), 3.0) == "must be <= 2");
  CHECK(setting_error(*find_run_setting("extrapolation"), 1.5) == "must be an integer");
  CHECK(setting_error(*find_run_setting("threads"), -1.0) == "must be >= 0");
  CHECK(setting_error(*find_run_setting("coupling_tol"), 0.0).empty());
  CHECK(setting_error(*find_run_setting("method"), std::string("euler")) == "unknown method (rk4, dopri5, colloc, tirk)");
  CHECK(setting_error(*find_run_setting("linear_solver"), std::string("lu")) ==
        "unknown linear solver (auto, dense, banded, klu, sparselu)");
  CHECK(setting_error(*find_run_setting("submodel_methods"), std::string("rk4,dopri5")).empty());
  CHECK(setting_error(*find_run_setting("submodel_methods"), std::string("rk4,euler")) ==
        "unknown method 'euler' (rk4, dopri5, colloc, tirk)");
  // An empty list is no list (none given), as before the settings were declared.
  CHECK(setting_error(*find_run_setting("submodel_methods"), std::string()).empty());
  CHECK(comma_items("").empty());
  CHECK(comma_items("a,,b") == std::vector<std::string>{"a", "", "b"});
  CHECK(methods_named("").empty());
}

TEST_CASE("run settings: a request overrides the model's block, as the reader reads it", "[settings]") {
  Model m;
  m.simulation.variant = "radau5";
  m.simulation.method = Method::tirk;
  m.simulation.output_interval = 0.1;
  RunRequest r;
  r.method = "colloc";
  r.output_every = 3;
  r.t_end = 2.0;
  apply_overrides(m, r);
  CHECK(m.simulation.method == Method::colloc);
  CHECK(m.simulation.variant.empty());  // tirk's variant is not colloc's
  CHECK(m.simulation.output_every == 3);
  CHECK(!m.simulation.output_interval);
  CHECK(m.simulation.t_end == 2.0);
  r = RunRequest{};
  r.t_end = -1.0;
  CHECK_THROWS_WITH(apply_overrides(m, r), "t_end: must be > t_start of the model");
  r = RunRequest{};
  r.method = "euler";
  CHECK_THROWS_WITH(apply_overrides(m, r), "method = euler: unknown method (rk4, dopri5, colloc, tirk)");
}

TEST_CASE("run settings: docs/run-settings.md holds the table the declarations make", "[settings]") {
  std::ifstream in(std::string(MBSFLOW_SOURCE) + "/docs/run-settings.md");
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str(), table = run_settings_table();
  const bool current = doc.find(table) != std::string::npos;
  if (!current) std::ofstream("run-settings-table.md") << table;  // to paste into the doc
  INFO("docs/run-settings.md's table is not the declarations' one: run-settings-table.md here has it");
  CHECK(current);
}
