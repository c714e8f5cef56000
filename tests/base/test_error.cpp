// Library messages name settings in braces; the library shows its names, a front end its own.
#include <catch2/catch.hpp>

#include "mbsflow/error.hpp"

using namespace mbsflow;

namespace {
std::string as_flag(const std::string& name, const std::string* value) {
  return "--" + name + (value ? " " + *value : "");
}
}  // namespace

TEST_CASE("error messages: settings in braces, rendered by the library and by a front end", "[base]") {
  const RunError e("diverged; try {step=1.2e-05} (or {method=dopri5}); {max_lag} too large");
  CHECK(std::string(e.what()) == "diverged; try step = 1.2e-05 (or method = dopri5); max_lag too large");
  CHECK(e.text() == "diverged; try {step=1.2e-05} (or {method=dopri5}); {max_lag} too large");
  CHECK(render(e.text(), as_flag) == "diverged; try --step 1.2e-05 (or --method dopri5); --max_lag too large");
  // passing a message on keeps its settings
  const std::exception& any = e;
  CHECK(error_text(any) == e.text());
  CHECK(error_text(std::runtime_error("{step}")) == "{step}");
}

TEST_CASE("error messages: braces that do not enclose a setting stay as they are", "[base]") {
  for (const char* text : {"expected '}' after {\"a\": 1}", "{", "}", "{}", "{Step}", "a {step", "{step=1{", "{x=}{y}"}) {
    INFO(text);
    const std::string expected = std::string(text) == "{x=}{y}" ? "x = y" : text;
    CHECK(InputError(text).what() == expected);
  }
}
