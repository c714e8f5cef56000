#include "json_tape.hpp"

#include <charconv>
#include <cstring>

namespace mbsflow {
namespace {

constexpr std::size_t npos = std::string_view::npos;

bool digit(char c) { return c >= '0' && c <= '9'; }

// A JSON number (-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?), converted as
// nlohmann-json converts it: the nearest double (an integer literal too, as its
// integer-to-double conversion rounds to nearest), -0 written as an integer being +0.
std::size_t parse_number(std::string_view text, std::size_t pos, double& out) {
  const std::size_t start = pos, n = text.size();
  if (pos < n && text[pos] == '-') ++pos;
  if (pos >= n || !digit(text[pos])) return npos;
  if (text[pos] == '0')
    ++pos;
  else
    while (pos < n && digit(text[pos])) ++pos;
  bool integer = true;
  if (pos < n && text[pos] == '.') {
    integer = false;
    if (++pos >= n || !digit(text[pos])) return npos;
    while (pos < n && digit(text[pos])) ++pos;
  }
  if (pos < n && (text[pos] == 'e' || text[pos] == 'E')) {
    integer = false;
    ++pos;
    if (pos < n && (text[pos] == '+' || text[pos] == '-')) ++pos;
    if (pos >= n || !digit(text[pos])) return npos;
    while (pos < n && digit(text[pos])) ++pos;
  }
  const auto r = std::from_chars(text.data() + start, text.data() + pos, out);
  if (r.ec != std::errc() || r.ptr != text.data() + pos) return npos;  // out of range: nlohmann's error
  if (integer && out == 0.0) out = 0.0;
  return pos;
}

bool matches(std::string_view text, std::size_t pos, const char* word) {
  const std::size_t len = std::strlen(word);
  return text.compare(pos, len, word) == 0;
}

struct TapeParser {
  std::string_view text;
  JsonTape& tape;

  std::size_t value(std::size_t pos, int depth) {
    if (pos >= text.size()) return npos;
    const std::size_t at = tape.entries.size();
    tape.entries.emplace_back();
    JsonTape::Entry& e = tape.entries.back();
    const char c = text[pos];
    std::size_t next = npos;
    if (c == '{' || c == '[') {
      if (depth <= 0) return npos;
      e.kind = c == '{' ? JsonTape::Kind::object : JsonTape::Kind::array;
      next = c == '{' ? object(pos + 1, depth - 1, at) : array(pos + 1, depth - 1, at);
    } else if (c == '"') {
      e.kind = JsonTape::Kind::string;
      next = parse_plain_json_string(text, pos, e.text);
    } else if (c == '-' || digit(c)) {
      e.kind = JsonTape::Kind::number;
      next = parse_number(text, pos, e.number);
    } else if (matches(text, pos, "true") || matches(text, pos, "false")) {
      e.kind = JsonTape::Kind::boolean;
      e.flag = c == 't';
      next = pos + (e.flag ? 4 : 5);
    } else if (matches(text, pos, "null")) {
      next = pos + 4;
    }
    tape.entries[at].end = static_cast<std::uint32_t>(tape.entries.size());
    return next;
  }

  std::size_t array(std::size_t pos, int depth, std::size_t at) {
    pos = skip_json_space(text, pos);
    if (pos < text.size() && text[pos] == ']') return pos + 1;
    for (std::uint32_t count = 1;; ++count) {
      pos = value(pos, depth);
      if (pos == npos) return npos;
      tape.entries[at].count = count;
      pos = skip_json_space(text, pos);
      if (pos >= text.size()) return npos;
      if (text[pos] == ']') return pos + 1;
      if (text[pos] != ',') return npos;
      pos = skip_json_space(text, pos + 1);
    }
  }

  std::size_t object(std::size_t pos, int depth, std::size_t at) {
    pos = skip_json_space(text, pos);
    if (pos < text.size() && text[pos] == '}') return pos + 1;
    for (std::uint32_t count = 1;; ++count) {
      std::string_view key;
      pos = parse_plain_json_string(text, pos, key);
      if (pos == npos) return npos;
      // A repeated key: nlohmann keeps the last; leave such text to it.
      for (std::size_t k = at + 1; k < tape.entries.size(); k = tape.entries[k + 1].end)
        if (tape.entries[k].text == key) return npos;
      JsonTape::Entry& k = tape.entries.emplace_back();
      k.kind = JsonTape::Kind::string;
      k.text = key;
      k.end = static_cast<std::uint32_t>(tape.entries.size());
      pos = skip_json_space(text, pos);
      if (pos >= text.size() || text[pos] != ':') return npos;
      pos = value(skip_json_space(text, pos + 1), depth);
      if (pos == npos) return npos;
      tape.entries[at].count = count;
      pos = skip_json_space(text, pos);
      if (pos >= text.size()) return npos;
      if (text[pos] == '}') return pos + 1;
      if (text[pos] != ',') return npos;
      pos = skip_json_space(text, pos + 1);
    }
  }
};

}  // namespace

const char* tape_type_name(JsonTape::Kind k) {
  switch (k) {
    case JsonTape::Kind::null: return "null";
    case JsonTape::Kind::boolean: return "boolean";
    case JsonTape::Kind::number: return "number";
    case JsonTape::Kind::string: return "string";
    case JsonTape::Kind::array: return "array";
    case JsonTape::Kind::object: return "object";
  }
  return "value";
}

std::size_t skip_json_space(std::string_view text, std::size_t pos) {
  while (pos < text.size() && (text[pos] == ' ' || text[pos] == '\n' || text[pos] == '\r' || text[pos] == '\t')) ++pos;
  return pos;
}

std::size_t parse_plain_json_string(std::string_view text, std::size_t pos, std::string_view& out) {
  if (pos >= text.size() || text[pos] != '"') return npos;
  const std::size_t start = pos + 1;
  for (std::size_t i = start; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '"') {
      out = text.substr(start, i - start);
      return i + 1;
    }
    if (c == '\\' || c < 0x20 || c > 0x7e) return npos;  // escapes, control and non-ASCII bytes: nlohmann's
  }
  return npos;
}

std::size_t parse_json_tape(std::string_view text, std::size_t pos, int max_depth, JsonTape& tape) {
  tape.entries.clear();
  return TapeParser{text, tape}.value(pos, max_depth);
}

}  // namespace mbsflow
