#include "json_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "json_depth.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

// nlohmann's message, less its "[json.exception...] parse error at line L, column C: " prefix.
std::string syntax_error(const nlohmann::json::parse_error& e, const std::string& name) {
  const std::string what = e.what();
  const std::size_t at = what.find("at line ");
  int line = 0, column = 0;
  if (at == std::string::npos || std::sscanf(what.c_str() + at, "at line %d, column %d", &line, &column) != 2)
    return format_input_error(name, {}, "", "invalid JSON: " + what);
  const std::size_t colon = what.find(": ", at);
  std::string detail = colon == std::string::npos ? what : what.substr(colon + 2);
  if (detail.find("invalid literal") != std::string::npos) detail += " (NaN and Infinity are not JSON numbers)";
  return format_input_error(name, {line, column}, "", "invalid JSON: " + detail);
}

// Line and column of a byte offset.
SourceLocation location_of(std::string_view text, std::size_t offset) {
  SourceLocation at;
  at.line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n'));
  const std::size_t line_start = text.rfind('\n', offset);
  at.column = static_cast<int>(offset - (line_start == std::string::npos ? 0 : line_start + 1)) + 1;
  return at;
}

// A number too large for a double ("1e999"): nlohmann names the literal, in quotes, but
// not its place; the first occurrence in the text gives line and column.
std::string overflow_error(const nlohmann::json::out_of_range& e, std::string_view text, const std::string& name) {
  const std::string what = e.what();
  const std::size_t open = what.find('\''), close = what.rfind('\'');
  const std::string number = open != std::string::npos && close > open ? what.substr(open + 1, close - open - 1) : "";
  SourceLocation at;
  if (const std::size_t offset = number.empty() ? std::string::npos : text.find(number); offset != std::string::npos)
    at = location_of(text, offset);
  return format_input_error(name, at, "", "number out of range" + (number.empty() ? "" : " (" + number + ")") +
                                              ": must be a finite number");
}

// Runs parse (nlohmann's parser on text) with the depth checked first and nlohmann's
// errors turned into InputErrors that point into the text.
template <class Parse>
auto parse_checked(std::string_view text, const std::string& name, Parse parse) {
  if (const std::size_t at = json_too_deep(text, max_json_depth); at != std::string::npos) {
    throw InputError(format_input_error(name, location_of(text, at), "", "nested deeper than " + std::to_string(max_json_depth) + " levels"));
  }
  try {
    return parse();
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(syntax_error(e, name));
  } catch (const nlohmann::json::out_of_range& e) {
    throw InputError(overflow_error(e, text, name));
  }
}

}  // namespace

std::string read_input_file(const std::string& path, const std::string& what, std::size_t max_bytes) {
  // A folder opens as a stream whose size reads as 2^63 - 1: said as what it is.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a folder, not a " + what);
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(path + ": cannot open the " + what);
  const auto size = static_cast<std::streamoff>(in.tellg());
  if (size > 0 && static_cast<std::size_t>(size) > max_bytes)
    throw InputError(path + ": the " + what + " has " + std::to_string(size) + " bytes, more than the " +
                     std::to_string(max_bytes) + " a " + what + " may have");
  in.seekg(0);
  if (size > 0) {  // a regular file: read in place (a string stream would hold the text twice)
    std::string text(static_cast<std::size_t>(size), '\0');
    if (!in.read(text.data(), size)) throw InputError(path + ": cannot read the " + what);
    return text;
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json parse_json_document(std::string_view text, const std::string& name) {
  return parse_checked(text, name, [&] { return nlohmann::json::parse(text); });
}

bool JsonEvents::parse_error(std::size_t, const std::string&, const nlohmann::json::exception& e) {
  if (const auto* p = dynamic_cast<const nlohmann::json::parse_error*>(&e)) throw *p;
  if (const auto* o = dynamic_cast<const nlohmann::json::out_of_range*>(&e)) throw *o;
  throw InputError(e.what());
}

void parse_json_events(std::string_view text, const std::string& name, JsonEvents& events) {
  parse_checked(text, name, [&] { return nlohmann::json::sax_parse(text, &events); });
}

std::string number_text(double v) {
  char buf[32];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string format_input_error(const std::string& file, SourceLocation at, const std::string& path, const std::string& what) {
  std::string s = file;
  if (at.line > 0) s += ":" + std::to_string(at.line) + ":" + std::to_string(at.column);
  s += ": ";
  if (!path.empty()) s += path + ": ";
  return s + what;
}

std::string JsonNode::path() const {
  if (!parent_) return index_ == no_index ? root_path_ : item_path(std::string(key_), index_);
  return index_ == no_index ? member_path(parent_->path(), std::string(key_)) : item_path(parent_->path(), index_);
}

void JsonNode::fail(const std::string& what) const {
  const std::string path = this->path();
  throw InputError(format_input_error(src_->file, src_->locations.value(path), path, what));
}

void JsonNode::fail_at_key(const std::string& what) const {
  const std::string path = this->path();
  throw InputError(format_input_error(src_->file, src_->locations.key(path), path, what));
}

bool JsonNode::is_string() const { return tape_ ? entry().kind == JsonTape::Kind::string : j_->is_string(); }

std::optional<std::uint32_t> JsonNode::tape_member(std::string_view key) const {
  const auto& e = tape_->entries;
  for (std::uint32_t k = at_ + 1; k < entry().end; k = e[k + 1].end)
    if (e[k].text == key) return k + 1;
  return std::nullopt;
}

std::uint32_t JsonNode::tape_item(std::size_t i) const {
  std::uint32_t k = at_ + 1;
  for (std::size_t n = 0; n < i; ++n) k = tape_->entries[k].end;
  return k;
}

void JsonNode::expect_object() const {
  const bool object = tape_ ? entry().kind == JsonTape::Kind::object : j_->is_object();
  if (!object) fail(std::string("must be an object (got ") + type_name() + ")");
}

bool JsonNode::has(const char* key) const {
  if (tape_) return entry().kind == JsonTape::Kind::object && tape_member(key).has_value();
  return j_->is_object() && j_->contains(key);
}

namespace {
[[noreturn]] void unknown_field(const JsonNode& member, std::span<const char* const> keys) {
  std::string list;
  for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
  member.fail_at_key("unknown field (expected one of: " + list + ")");
}
bool known(std::string_view key, std::span<const char* const> keys) {
  for (const char* k : keys)
    if (key == k) return true;
  return false;
}
}  // namespace

void JsonNode::allow_only(std::initializer_list<const char*> keys) const {
  allow_only(std::span<const char* const>(keys.begin(), keys.size()));
}

void JsonNode::allow_only(std::span<const char* const> keys) const {
  expect_object();
  if (tape_) {
    const auto& e = tape_->entries;
    for (std::uint32_t k = at_ + 1; k < entry().end; k = e[k + 1].end)
      if (!known(e[k].text, keys)) unknown_field(JsonNode(k + 1, *this, e[k].text, no_index), keys);
    return;
  }
  for (auto it = j_->begin(); it != j_->end(); ++it)
    if (!known(it.key(), keys)) unknown_field(member(it.value(), it.key()), keys);
}

JsonNode JsonNode::operator[](const char* key) const {
  if (auto n = find(key)) return *n;
  fail(std::string("missing field '") + key + "'");
}

std::optional<JsonNode> JsonNode::find(const char* key) const {
  expect_object();
  if (tape_) {
    const auto at = tape_member(key);
    if (!at) return std::nullopt;
    return JsonNode(*at, *this, key, no_index);
  }
  const auto it = j_->find(key);
  if (it == j_->end()) return std::nullopt;
  return member(*it, key);
}

std::size_t JsonNode::array_size() const {
  const bool array = tape_ ? entry().kind == JsonTape::Kind::array : j_->is_array();
  if (!array) fail(std::string("must be an array (got ") + type_name() + ")");
  return tape_ ? entry().count : j_->size();
}

JsonNode JsonNode::item(std::size_t i) const {
  if (tape_) return JsonNode(tape_item(i), *this, {}, i);
  return JsonNode(j_->at(i), *this, {}, i);
}

double JsonNode::number() const {
  const bool is_number = tape_ ? entry().kind == JsonTape::Kind::number : j_->is_number();
  if (!is_number) fail(std::string("must be a number (got ") + type_name() + ")");
  const double v = tape_ ? entry().number : j_->get<double>();
  if (!std::isfinite(v)) fail("must be a finite number");
  return v;
}

double JsonNode::positive() const {
  const double v = number();
  if (!(v > 0.0)) fail("must be > 0 (got " + number_text(v) + ")");
  return v;
}

double JsonNode::non_negative() const {
  const double v = number();
  if (v < 0.0) fail("must be >= 0 (got " + number_text(v) + ")");
  return v;
}

long JsonNode::integer(long min, long max) const {
  const double v = number();
  if (v != std::floor(v) || std::abs(v) > static_cast<double>(max_integer))
    fail("must be an integer (got " + number_text(v) + ")");
  if (v < static_cast<double>(min)) fail("must be >= " + std::to_string(min) + " (got " + number_text(v) + ")");
  if (v > static_cast<double>(max)) fail("must be <= " + std::to_string(max) + " (got " + number_text(v) + ")");
  return static_cast<long>(v);
}

std::string JsonNode::string() const {
  if (!is_string()) fail(std::string("must be a string (got ") + type_name() + ")");
  return tape_ ? std::string(entry().text) : j_->get<std::string>();
}

bool JsonNode::boolean() const {
  const bool is_boolean = tape_ ? entry().kind == JsonTape::Kind::boolean : j_->is_boolean();
  if (!is_boolean) fail("must be true or false");
  return tape_ ? entry().flag : j_->get<bool>();
}

void JsonNode::fixed(double* out, std::size_t n) const {
  auto wrong_size = [&](std::size_t size) {
    fail("must have " + std::to_string(n) + " numbers (got " + std::to_string(size) + ")");
  };
  if (!tape_) {
    const std::vector<double> v = numbers();
    if (v.size() != n) wrong_size(v.size());
    std::copy(v.begin(), v.end(), out);
    return;
  }
  // As numbers() then the size: each item checked first, but without a vector.
  const std::size_t size = tape_numbers([&](std::size_t i, double v) {
    if (i < n) out[i] = v;
  });
  if (size != n) wrong_size(size);
}

template <class Take>
std::size_t JsonNode::tape_numbers(Take take) const {
  const std::size_t size = array_size();
  std::uint32_t k = at_ + 1;
  for (std::size_t i = 0; i < size; ++i, k = tape_->entries[k].end) {
    const JsonTape::Entry& x = tape_->entries[k];
    // The item's own node (and path) only to report a bad number.
    take(i, x.kind == JsonTape::Kind::number && std::isfinite(x.number) ? x.number : item(i).number());
  }
  return size;
}

std::vector<double> JsonNode::numbers() const {
  const std::size_t n = array_size();
  std::vector<double> v(n);
  if (tape_) {
    tape_numbers([&](std::size_t i, double x) { v[i] = x; });
    return v;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const nlohmann::json& x = (*j_)[i];
    // The item's own node (and path) only to report a bad number.
    v[i] = x.is_number() && std::isfinite(x.get<double>()) ? x.get<double>() : item(i).number();
  }
  return v;
}

}  // namespace mbsflow
