#pragma once
// Appends JSON text to a string without building a document: numbers in their shortest
// round-trip form (std::to_chars), strings escaped. The model writer writes a million
// bodies with it; nlohmann's per-item documents cost about 10 us each.
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace mbsflow::json_text {

// As nlohmann writes them: an integral double keeps a ".0" so that it reads back as a
// floating-point number; NaN and infinities (not JSON) become null.
inline void write(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  const std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));
  out += text;
  if (text.find_first_of(".e") == std::string_view::npos) out += ".0";
}

template <class I, std::enable_if_t<std::is_integral_v<I> && !std::is_same_v<I, bool>, int> = 0>
void write(std::string& out, I v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

inline void write(std::string& out, bool v) { out += v ? "true" : "false"; }

inline void write(std::string& out, std::string_view s) {
  static const char* hex = "0123456789abcdef";
  out += '"';
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          out += "\\u00";
          out += hex[(c >> 4) & 0xf];
          out += hex[c & 0xf];
        } else {
          out += c;
        }
    }
  }
  out += '"';
}
inline void write(std::string& out, const std::string& s) { write(out, std::string_view(s)); }
inline void write(std::string& out, const char* s) { write(out, std::string_view(s)); }

template <class Range>
void write_array(std::string& out, const Range& r) {
  out += '[';
  bool first = true;
  for (const auto& v : r) {
    if (!first) out += ',';
    first = false;
    write(out, v);
  }
  out += ']';
}
template <class T, std::size_t N>
void write(std::string& out, const std::array<T, N>& a) { write_array(out, a); }
template <class T>
void write(std::string& out, const std::vector<T>& v) { write_array(out, v); }

// One object: fields in the order given, commas between them.
class Object {
 public:
  explicit Object(std::string& out) : out_(out) { out_ += '{'; }
  Object(const Object&) = delete;
  Object& operator=(const Object&) = delete;
  ~Object() { out_ += '}'; }

  template <class T>
  Object& operator()(std::string_view key, const T& value) {
    write_key(key);
    write(out_, value);
    return *this;
  }
  // A value whose JSON text is already written (by write()).
  Object& raw(std::string_view key, std::string_view text) {
    write_key(key);
    out_ += text;
    return *this;
  }
  // A nested object, filled by fill(Object&).
  template <class Fill>
  Object& object(std::string_view key, Fill&& fill) {
    write_key(key);
    Object inner(out_);
    fill(inner);
    return *this;
  }

 private:
  void write_key(std::string_view key) {
    if (!first_) out_ += ',';
    first_ = false;
    write(out_, key);
    out_ += ':';
  }
  std::string& out_;
  bool first_ = true;
};

}  // namespace mbsflow::json_text
