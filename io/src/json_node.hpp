#pragma once
// A JSON value with its field path and the file it came from, with typed getters that
// throw InputError("file:line:col: path: what is wrong") on bad input.
#include <array>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "json_locations.hpp"
#include "json_tape.hpp"

namespace mbsflow {

struct JsonSource {
  std::string file;
  JsonLocations locations;
};

// A child node refers to its parent and spells its path only when it reports an error (a
// million-body model has tens of millions of fields): a child must not outlive its parent,
// which holds for nodes made and used within one reading function.
// A node views either a nlohmann-json value or an entry of a JsonTape (the fast reader's):
// the getters behave the same on both.
class JsonNode {
 public:
  JsonNode(const nlohmann::json& j, std::string path, const JsonSource& src) : j_(&j), src_(&src), root_path_(std::move(path)) {}
  // An item of a top-level list (path "list[index]", spelt only for a message).
  JsonNode(const JsonTape& tape, const char* list, std::size_t index, const JsonSource& src)
      : tape_(&tape), src_(&src), key_(list), index_(index) {}

  bool is_string() const;
  std::string path() const;

  [[noreturn]] void fail(const std::string& what) const;          // points at the value
  [[noreturn]] void fail_at_key(const std::string& what) const;   // points at the member's key

  // Objects.
  void expect_object() const;
  void allow_only(std::initializer_list<const char*> keys) const;  // unknown field -> error
  void allow_only(std::span<const char* const> keys) const;
  bool has(const char* key) const;
  JsonNode operator[](const char* key) const;                        // required member
  std::optional<JsonNode> find(const char* key) const;               // optional member

  // Arrays.
  std::size_t array_size() const;  // fails unless an array
  JsonNode item(std::size_t i) const;

  // Scalars.
  double number() const;  // finite
  double positive() const;
  double non_negative() const;
  // An integer in [min, max]; nothing is converted before it is known to fit.
  long integer(long min, long max = max_integer) const;
  static constexpr long max_integer = 9'000'000'000'000'000;  // below 2^53: every one exact in a double
  std::string string() const;
  bool boolean() const;  // true or false
  std::vector<double> numbers() const;  // array of finite numbers, any length
  template <std::size_t N>
  std::array<double, N> fixed() const {
    std::array<double, N> a{};
    fixed(a.data(), N);
    return a;
  }

 private:
  JsonNode(const nlohmann::json& j, const JsonNode& parent, std::string_view key, std::size_t index)
      : j_(&j), src_(parent.src_), parent_(&parent), key_(key), index_(index) {}
  JsonNode(std::uint32_t at, const JsonNode& parent, std::string_view key, std::size_t index)
      : tape_(parent.tape_), at_(at), src_(parent.src_), parent_(&parent), key_(key), index_(index) {}
  static constexpr std::size_t no_index = static_cast<std::size_t>(-1);
  JsonNode member(const nlohmann::json& j, std::string_view key) const { return JsonNode(j, *this, key, no_index); }
  const JsonTape::Entry& entry() const { return tape_->entries[at_]; }
  void fixed(double* out, std::size_t n) const;  // exactly n finite numbers
  const char* type_name() const { return tape_ ? tape_type_name(entry().kind) : j_->type_name(); }
  std::optional<std::uint32_t> tape_member(std::string_view key) const;  // the value's entry
  std::uint32_t tape_item(std::size_t i) const;
  // Hands each item of this tape array to take(index, value), each a finite number (or
  // fails naming it); returns the array's size.
  template <class Take>
  std::size_t tape_numbers(Take take) const;

  const nlohmann::json* j_ = nullptr;  // or:
  const JsonTape* tape_ = nullptr;
  std::uint32_t at_ = 0;               // the entry in tape_
  const JsonSource* src_;
  const JsonNode* parent_ = nullptr;  // none: a root, whose path is root_path_
  std::string_view key_;              // a member's key (held by the parsed document or the caller)
  std::size_t index_ = no_index;      // an array item's index
  std::string root_path_;
};

// "file:line:col: path: what" with whatever of these is known.
std::string format_input_error(const std::string& file, SourceLocation at, const std::string& path, const std::string& what);
std::string number_text(double v);  // shortest text that reads back as v
// The whole of an input file; InputError("path: cannot open the WHAT") if it cannot be
// read, or if it is larger than max_bytes (checked before anything is read).
std::string read_input_file(const std::string& path, const std::string& what, std::size_t max_bytes);
// Input files nest no deeper than this (a model needs 5 levels): deeper text is refused
// before it is parsed, since parsing and locating cost grows with depth.
inline constexpr int max_json_depth = 64;
// Parses a JSON document; InputError("name:line:col: invalid JSON: ...") if it is not one,
// or if it nests deeper than max_json_depth.
nlohmann::json parse_json_document(std::string_view text, const std::string& name);
// A handler of parse events whose syntax errors throw as the document parser's do.
struct JsonEvents : nlohmann::json_sax<nlohmann::json> {
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::json::exception& e) override;
};
// Parses a JSON document into events, with parse_json_document's checks and errors.
void parse_json_events(std::string_view text, const std::string& name, JsonEvents& events);

}  // namespace mbsflow
