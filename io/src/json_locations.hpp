#pragma once
// Line and column of a value in a JSON text, by field path ("bodies[3].mass"), so that
// input errors can point into the file. nlohmann-json keeps no positions. Nothing is
// computed until a location is asked for (only when there is an error to report): then
// one pass over the text finds it, building no path that does not lead to it.
#include <string>
#include <string_view>

namespace mbsflow {

struct SourceLocation {
  int line = 0;    // 1-based; 0 = unknown
  int column = 0;  // 1-based, in bytes
};

class JsonLocations {
 public:
  struct Entry {
    SourceLocation key, value;
  };

  JsonLocations() = default;
  // The text must be valid JSON (parse it with nlohmann first; nothing is validated here)
  // and must outlive this object: it is viewed, not copied.
  explicit JsonLocations(std::string_view text) : text_(text) {}
  SourceLocation value(const std::string& path) const;
  SourceLocation key(const std::string& path) const;  // the member's key; the value for array items

 private:
  Entry find(const std::string& path) const;
  std::string_view text_;
};

// Field paths as used in messages: "bodies", "bodies[3]", "bodies[3].mass".
std::string member_path(const std::string& parent, const std::string& key);
std::string item_path(const std::string& parent, std::size_t index);

}  // namespace mbsflow
