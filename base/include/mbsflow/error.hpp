#pragma once
// The one exception hierarchy of mbsflow. Every error the library throws derives from Error.
//
// Messages name the settings they refer to in braces, "{step=1.2e-05}" or "{macro_step}",
// by their names in the library (RunOptions, LooseOptions and model fields). what() shows
// them that way ("step = 1.2e-05", "macro_step"); a front end shows its own names for them
// with render(text(), ...): the CLI shows the flags ("--step 1.2e-05", "--macro-step").
#include <functional>
#include <stdexcept>
#include <string>

namespace mbsflow {

// How a front end writes a setting: its name, and its value if the message gives one.
using SettingWriter = std::function<std::string(const std::string& name, const std::string* value)>;

// The message with every {name} or {name=value} written by `write`; other text, braces
// that do not enclose a lower-case name included, stays as it is.
inline std::string render(const std::string& text, const SettingWriter& write) {
  std::string out;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t open = text.find('{', at);
    if (open == std::string::npos) break;
    std::size_t end = open + 1;
    while (end < text.size() && ((text[end] >= 'a' && text[end] <= 'z') || text[end] == '_')) ++end;
    const std::size_t close = text.find_first_of("{}", end);
    const bool named = end > open + 1 && end < text.size() && (text[end] == '}' || text[end] == '=') &&
                       close != std::string::npos && text[close] == '}';
    out.append(text, at, (named ? open : open + 1) - at);
    at = open + 1;
    if (!named) continue;
    const std::string name = text.substr(open + 1, end - open - 1);
    if (text[end] == '=') {
      const std::string value = text.substr(end + 1, close - end - 1);
      out += write(name, &value);
    } else {
      out += write(name, nullptr);
    }
    at = close + 1;
  }
  out.append(text, at);
  return out;
}

// The library's own way: "step = 1.2e-05", "macro_step".
inline std::string library_setting(const std::string& name, const std::string* value) {
  return value ? name + " = " + *value : name;
}

struct Error : std::runtime_error {
  explicit Error(const std::string& text) : std::runtime_error(render(text, library_setting)), text_(text) {}
  // The message with its settings still in braces, for render().
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// Bad input: a model, a setting or a command-line value. The CLI exits with code 2.
struct InputError : Error {
  using Error::Error;
};

// Bad input that shows only once a model is set up (a rigid joint its bodies do not meet):
// the front end, which knows the model's file, names it.
struct ModelError : InputError {
  using InputError::InputError;
};

// A run that could not be completed (diverged, step too small, peer lost). Exit code 1.
struct RunError : Error {
  using Error::Error;
};

// Any exception's message, an Error's with its settings still in braces (to pass on).
inline std::string error_text(const std::exception& e) {
  if (const auto* m = dynamic_cast<const Error*>(&e)) return m->text();
  return e.what();
}

}  // namespace mbsflow
