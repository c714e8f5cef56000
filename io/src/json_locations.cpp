#include "json_locations.hpp"

#include <optional>

namespace mbsflow {

std::string member_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string item_path(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

namespace {

// One pass over the text in search of one path: values off the way to it are skipped
// (their lines counted) without building their paths.
class Scanner {
 public:
  Scanner(std::string_view text, const std::string& target) : s_(text), target_(target) {}

  std::optional<JsonLocations::Entry> run() {
    value("", {1, 1});
    return found_;
  }

 private:
  // Whether path is the target or leads to it.
  bool on_the_way(const std::string& path) const {
    if (target_.compare(0, path.size(), path) != 0) return false;
    if (target_.size() == path.size() || path.empty()) return true;
    const char next = target_[path.size()];
    return next == '.' || next == '[';
  }

  void value(const std::string& path, SourceLocation key) {
    skip_space();
    if (path == target_) {
      found_ = JsonLocations::Entry{key, here()};
      return;
    }
    if (pos_ >= s_.size()) return;
    const char c = s_[pos_];
    if (c == '{') {
      advance();
      while (!found_) {
        skip_space();
        if (pos_ >= s_.size() || closing(s_[pos_])) break;
        if (s_[pos_] == ',') { advance(); continue; }
        const SourceLocation k = here();
        const std::string name = string();
        skip_space();
        if (pos_ < s_.size() && s_[pos_] == ':') advance();
        const std::string member = member_path(path, name);
        if (on_the_way(member)) {
          value(member, k);
        } else {
          skip_value();
        }
      }
      advance();
    } else if (c == '[') {
      advance();
      std::size_t i = 0;
      while (!found_) {
        skip_space();
        if (pos_ >= s_.size() || closing(s_[pos_])) break;
        if (s_[pos_] == ',') { advance(); continue; }
        const SourceLocation item = here();
        const std::string element = item_path(path, i++);
        if (on_the_way(element)) {
          value(element, item);
        } else {
          skip_value();
        }
      }
      advance();
    } else {
      skip_value();
    }
  }

  // Past one value, nested or not, counting lines; strings are skipped whole so that
  // brackets inside them do not count.
  void skip_value() {
    skip_space();
    int depth = 0;
    while (pos_ < s_.size()) {
      const char c = s_[pos_];
      if (c == '"') {
        skip_string();
      } else if (c == '{' || c == '[') {
        ++depth;
        advance();
      } else if (c == '}' || c == ']') {
        if (depth == 0) return;  // the end of the enclosing container
        --depth;
        advance();
        if (depth == 0) return;
      } else if (depth == 0 && (c == ',' || space(c))) {
        return;
      } else {
        advance();
      }
      if (depth == 0 && c == '"') return;
    }
  }

  // Either closer ends a container: the text past the point where a reading error was
  // thrown was never parsed and need not be valid JSON, yet each loop must end.
  static bool closing(char c) { return c == '}' || c == ']'; }
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
  void skip_string() {
    advance();  // opening quote
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\') advance();
      advance();
    }
    advance();  // closing quote
  }
  // A string literal decoded as the parser decodes it (\u escapes to UTF-8, surrogate
  // pairs joined), so that a key written with escapes still matches its path.
  std::string string() {
    std::string out;
    advance();  // opening quote
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\' && pos_ + 1 < s_.size()) {
        advance();
        const char e = s_[pos_];
        if (e == 'u') {
          append_utf8(out, code_point());
          continue;
        }
        out += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e == 'b' ? '\b' : e == 'f' ? '\f' : e;
      } else {
        out += s_[pos_];
      }
      advance();
    }
    advance();  // closing quote
    return out;
  }
  // At the 'u' of \uXXXX: the code point, with a following low surrogate joined; leaves
  // the position after the last hex digit read.
  unsigned code_point() {
    unsigned c = hex4();
    if (c >= 0xD800 && c < 0xDC00 && pos_ + 1 < s_.size() && s_[pos_] == '\\' && s_[pos_ + 1] == 'u') {
      const std::size_t at = pos_;
      const int line = line_, col = col_;
      advance();
      const unsigned low = hex4();
      if (low >= 0xDC00 && low < 0xE000) return 0x10000 + ((c - 0xD800) << 10) + (low - 0xDC00);
      pos_ = at, line_ = line, col_ = col;  // not a pair: the second escape is read on its own
    }
    return c;
  }
  unsigned hex4() {
    advance();  // the 'u'
    unsigned v = 0;
    for (int i = 0; i < 4 && pos_ < s_.size(); ++i) {
      const char h = s_[pos_];
      const unsigned d = h >= '0' && h <= '9' ? unsigned(h - '0') : h >= 'a' && h <= 'f' ? unsigned(h - 'a' + 10)
                       : h >= 'A' && h <= 'F' ? unsigned(h - 'A' + 10) : 0u;
      v = v * 16 + d;
      advance();
    }
    return v;
  }
  static void append_utf8(std::string& out, unsigned c) {
    if (c < 0x80) {
      out += char(c);
    } else if (c < 0x800) {
      out += char(0xC0 | (c >> 6)), out += char(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += char(0xE0 | (c >> 12)), out += char(0x80 | ((c >> 6) & 0x3F)), out += char(0x80 | (c & 0x3F));
    } else {
      out += char(0xF0 | (c >> 18)), out += char(0x80 | ((c >> 12) & 0x3F)), out += char(0x80 | ((c >> 6) & 0x3F));
      out += char(0x80 | (c & 0x3F));
    }
  }

  std::string_view s_;
  const std::string& target_;
  std::optional<JsonLocations::Entry> found_;
  std::size_t pos_ = 0;
  int line_ = 1, col_ = 1;
};

}  // namespace

JsonLocations::Entry JsonLocations::find(const std::string& path) const {
  return Scanner(text_, path).run().value_or(Entry{});
}

SourceLocation JsonLocations::value(const std::string& path) const { return find(path).value; }

SourceLocation JsonLocations::key(const std::string& path) const { return find(path).key; }

}  // namespace mbsflow
