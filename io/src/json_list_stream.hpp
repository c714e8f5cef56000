#pragma once
// A JSON document read as a stream of events, in which the items of chosen top-level
// lists ("bodies", "joints", ...) are handed over one at a time as each is complete, so
// that a model of a million bodies is never held as one document tree: only the rest of
// the document (with those lists left empty) and one item at a time.
#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace mbsflow {

struct JsonListHandlers {
  // The top-level members that are streamed when they are arrays (any other value of
  // theirs stays in the document tree, for the reader to refuse as it would).
  std::vector<std::string> lists;
  std::function<void(std::size_t list, std::size_t index, nlohmann::json&& item)> item;
  std::function<void(std::size_t list, std::size_t count)> end;  // after a list's last item
};

// Parses the text (with parse_json_document's checks and errors); returns the document
// with each streamed list an empty array. A streamed list named twice is an error.
nlohmann::json parse_json_streaming_lists(std::string_view text, const std::string& name, const JsonListHandlers& handlers);

}  // namespace mbsflow
