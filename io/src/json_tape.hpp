#pragma once
// A fast reader for the plain JSON of large models: one value parsed into a flat array of
// entries in document order (a "tape"), strings viewed in the text, numbers converted
// with std::from_chars. It takes a strict subset of JSON on purpose: strings without
// escapes or bytes outside printable ASCII, objects without repeated keys, numbers that
// fit a double, bounded nesting. Anything else (valid JSON or not) makes it give up, and
// the caller reads the text with nlohmann-json instead, whose checks and messages stand.
// A million-body model is read about five times faster this way: no tree of maps, one
// buffer reused for every item.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace mbsflow {

struct JsonTape {
  enum class Kind : std::uint8_t { null, boolean, number, string, array, object };
  struct Entry {
    Kind kind = Kind::null;
    bool flag = false;       // a boolean's value
    std::uint32_t count = 0;  // an array's items, an object's members
    std::uint32_t end = 0;    // the index after this value's entries
    double number = 0.0;
    std::string_view text;   // a string's characters, an object member's key (on the key entry)
  };
  // An object is followed by its members, each a string entry (the key) then the value's
  // entries; an array by its items' entries.
  std::vector<Entry> entries;
};

// The type's name as nlohmann-json spells it ("object", "number", ...).
const char* tape_type_name(JsonTape::Kind k);

// Skips JSON whitespace from pos; the position of the first other character (or size).
std::size_t skip_json_space(std::string_view text, std::size_t pos);

// Parses the value at text[pos] (no leading whitespace) into tape (cleared first), nested
// at most max_depth deep; the position after it, or npos where the value is outside the
// subset above (or not JSON).
std::size_t parse_json_tape(std::string_view text, std::size_t pos, int max_depth, JsonTape& tape);

// A string at text[pos] within the subset; the position after its closing quote (its
// characters in out), or npos.
std::size_t parse_plain_json_string(std::string_view text, std::size_t pos, std::string_view& out);

}  // namespace mbsflow
