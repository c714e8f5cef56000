#include "json_tape_list.hpp"

namespace mbsflow::tape_list {

bool ListParser::next(JsonTape& tape) {
  constexpr std::size_t npos = std::string_view::npos;
  auto stop = [&](std::size_t at) {
    pos = at;
    done = true;
  };
  if (done) return false;
  pos = parse_json_tape(text, pos, item_depth, tape);
  if (pos == npos) {
    done = true;
    return false;
  }
  ++next_index;
  const std::size_t after = skip_json_space(text, pos);
  if (after >= text.size())
    stop(npos);
  else if (text[after] == ']')
    stop(after + 1);
  else if (text[after] != ',')
    stop(npos);
  else
    pos = skip_json_space(text, after + 1);
  return true;
}

}  // namespace mbsflow::tape_list
