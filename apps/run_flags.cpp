#include "run_flags.hpp"

#include <cmath>
#include <cstdlib>
#include <map>

#include "commands.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow::cli {
namespace {

// The setting's range or choices as a CLI11 check, with the messages Python gives.
CLI::Validator check_of(const RunSetting& s) {
  std::string what;
  if (!s.allowed().empty()) {
    for (const std::string& c : s.allowed()) what += (what.empty() ? "" : ",") + c;
    what = s.list ? "LIST of {" + what + "}" : "{" + what + "}";
  } else if (s.is_number()) {
    const auto n = [](double v) { return std::to_string(static_cast<long long>(v)); };
    const bool whole = s.lo == std::floor(s.lo);
    if (s.lo_open && whole)
      what = "> " + n(s.lo);
    else if (std::isfinite(s.lo) && std::isfinite(s.hi))
      what = "in [" + n(s.lo) + " - " + n(s.hi) + "]";
    else if (std::isfinite(s.lo))
      what = ">= " + n(s.lo);
  }
  return CLI::Validator(
      [&s](std::string& text) -> std::string {
        const auto got = [&](const std::string& e) { return e.empty() ? e : e + " (got " + text + ")"; };
        if (!s.is_number()) return got(setting_error(s, text));
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') return "";  // CLI11's conversion names what is wrong
        return got(setting_error(s, v));
      },
      what);
}

}  // namespace

std::string flag_for(const std::string& setting, const std::string* value) {
  const RunSetting* s = find_run_setting(setting);
  std::string flag;
  if (s && *s->flag) {
    flag = s->long_flag();
  } else {
    flag = "--" + setting;
    std::replace(flag.begin(), flag.end(), '_', '-');
  }
  return flag + (value ? " " + *value : "");
}

void add_run_settings(CLI::App* sub, RunRequest& request) {
  std::map<std::string, CLI::Option*> made;
  for (const RunSetting& s : run_settings()) {
    if (!(s.places & in_cli)) continue;
    std::string help = render(s.help, flag_for);
    if (s.places & in_model) help += " (overrides simulation." + std::string(s.name) + ")";
    CLI::Option* o = std::visit(
        [&](auto member) -> CLI::Option* {
          auto& value = request.*member;
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, bool>)
            return sub->add_flag(s.flag, value, help);
          else
            return sub->add_option(s.flag, value, help);
        },
        s.field);
    if (!s.is_flag()) o->check(check_of(s));
    if (!default_text(s).empty() && !s.is_flag()) o->capture_default_str();
    made[s.name] = o;
  }
  for (const RunSetting& s : run_settings()) {
    if (!(s.places & in_cli)) continue;
    if (*s.needs) made.at(s.name)->needs(made.at(s.needs));
    for (const std::string& other : comma_items(s.excludes)) made.at(s.name)->excludes(made.at(other));
  }
}

}  // namespace mbsflow::cli
