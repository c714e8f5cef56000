#include "json_locations.hpp"

namespace mbsflow {

std::string member_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string item_path(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

namespace {

class Scanner {
 public:
  Scanner(std::string_view text, std::unordered_map<std::string, JsonLocations::Entry>& out)
      : s_(text), out_(out) {}

  void value(const std::string& path, SourceLocation key) {
    skip_space();
    out_[path] = {key, here()};
    if (pos_ >= s_.size()) return;
    const char c = s_[pos_];
    if (c == '{') {
      advance();
      while (true) {
        skip_space();
        if (pos_ >= s_.size() || s_[pos_] == '}') break;
        if (s_[pos_] == ',') { advance(); continue; }
        const SourceLocation k = here();
        const std::string name = string();
        skip_space();
        if (pos_ < s_.size() && s_[pos_] == ':') advance();
        value(member_path(path, name), k);
      }
      advance();
    } else if (c == '[') {
      advance();
      std::size_t i = 0;
      while (true) {
        skip_space();
        if (pos_ >= s_.size() || s_[pos_] == ']') break;
        if (s_[pos_] == ',') { advance(); continue; }
        const SourceLocation item = here();
        value(item_path(path, i++), item);
      }
      advance();
    } else if (c == '"') {
      string();
    } else {
      while (pos_ < s_.size() && s_[pos_] != ',' && s_[pos_] != '}' && s_[pos_] != ']' && !space(s_[pos_])) advance();
    }
  }

 private:
  static bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  SourceLocation here() const { return {line_, col_}; }
  void advance() {
    if (pos_ >= s_.size()) return;
    if (s_[pos_] == '\n') {
      ++line_;
      col_ = 1;
    } else {
      ++col_;
    }
    ++pos_;
  }
  void skip_space() {
    while (pos_ < s_.size() && space(s_[pos_])) advance();
  }
  // A string literal; simple escapes decoded, \u escapes kept as written.
  std::string string() {
    std::string out;
    advance();  // opening quote
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\' && pos_ + 1 < s_.size()) {
        advance();
        const char e = s_[pos_];
        out += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'u' ? 'u' : e;
      } else {
        out += s_[pos_];
      }
      advance();
    }
    advance();  // closing quote
    return out;
  }

  std::string_view s_;
  std::unordered_map<std::string, JsonLocations::Entry>& out_;
  std::size_t pos_ = 0;
  int line_ = 1, col_ = 1;
};

}  // namespace

JsonLocations::JsonLocations(std::string_view text) { Scanner(text, map_).value("", {1, 1}); }

SourceLocation JsonLocations::value(const std::string& path) const {
  const auto it = map_.find(path);
  return it == map_.end() ? SourceLocation{} : it->second.value;
}

SourceLocation JsonLocations::key(const std::string& path) const {
  const auto it = map_.find(path);
  return it == map_.end() ? SourceLocation{} : it->second.key;
}

}  // namespace mbsflow
