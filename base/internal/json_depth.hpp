#pragma once
// Where JSON text first opens a bracket deeper than max_depth, or npos. A scan that only
// skips strings, run before any parser sees text from outside: parsing, locating and
// destroying a value cost grows with its nesting (and recursion may overflow the stack).
#include <cstddef>
#include <string_view>

namespace mbsflow {

inline std::size_t json_too_deep(std::string_view text, int max_depth) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > max_depth) return i;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return std::string_view::npos;
}

}  // namespace mbsflow
