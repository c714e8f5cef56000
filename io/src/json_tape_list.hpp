#pragma once
// The items of a JSON list read by the fast reader (json_tape.hpp) in a pipeline: one
// thread parses the text into tapes, any thread makes each item's record from its tape
// (several batches at once), and one thread at a time takes the records in the list's
// order. Before, one thread did all three for a million-body model: about a quarter, two
// fifths and a quarter of the work (the last mostly the kernel zeroing the records' pages).
#include <tbb/parallel_pipeline.h>

#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include "json_tape.hpp"
#include "tsan_annotations.hpp"

namespace mbsflow {

namespace tape_list {

// Items parsed, made and taken together, so that the threads meet once per batch.
template <class Record>
struct Batch {
  static constexpr std::size_t capacity = 256;
  std::size_t first = 0;  // the index of the first item
  std::size_t size = 0;
  std::array<JsonTape, capacity> tapes;
  std::array<Record, capacity> records;
  // ThreadSanitizer's tokens (tsan_annotations.hpp), which does not see the pipeline's
  // orderings: the batch parsed, made, and taken (free again).
  char parsed = 0, made = 0, taken = 0;
};

// Parses the batches' items from pos on, item by item: pos ends after the list's ']' (the
// list ended), at npos (an item outside the subset), or at the next item's start.
struct ListParser {
  std::string_view text;
  int item_depth;
  std::size_t pos;
  std::size_t next_index = 0;
  bool done = false;

  // Parses the next item into tape; false when there is none (done).
  bool next(JsonTape& tape);
};

// ThreadSanitizer's token for a pipeline's start: at namespace scope, so that a stage can
// take it before it reads its captures (which the starting thread wrote).
inline const char pipeline_start = 0;

}  // namespace tape_list

// Parses the list whose '[' is at text[pos], each item nested at most item_depth deep;
// make(index, tape) returns each item's Record (on any thread, for several items at once:
// it may read only what no take changes), then take(index, tape, record) gets them one at
// a time in the list's order. Returns the position after the list's ']', or npos where an
// item is outside the fast reader's subset (the items before it were taken). An exception
// from make or take stops the reading and reaches the caller.
template <class Record, class Make, class Take>
std::size_t read_tape_list(std::string_view text, std::size_t pos, int item_depth, Make make, Take take) {
  using Batch = tape_list::Batch<Record>;
  pos = skip_json_space(text, pos + 1);
  if (pos < text.size() && text[pos] == ']') return pos + 1;
  // A batch is reused once the pipeline has let `tokens` later ones in: by then it has
  // passed all three stages.
  constexpr std::size_t tokens = 4;
  std::vector<Batch> batches(tokens);
  std::size_t next_batch = 0;
  tape_list::ListParser parser{text, item_depth, pos};
  const char parse_turn = 0, take_turn = 0;
  auto parse = [&](tbb::flow_control& fc) -> Batch* {
    happens_after(&tape_list::pipeline_start);
    happens_after(&parse_turn);
    const ReleaseOnExit turn{&parse_turn};
    if (parser.done) {
      fc.stop();
      return nullptr;
    }
    Batch& b = batches[next_batch++ % tokens];
    happens_after(&b.taken);
    b.first = parser.next_index;
    b.size = 0;
    while (b.size < Batch::capacity && parser.next(b.tapes[b.size])) ++b.size;
    happens_before(&b.parsed);
    return &b;
  };
  auto make_all = [&](Batch* b) {
    happens_after(&tape_list::pipeline_start);
    happens_after(&b->parsed);
    const ReleaseOnExit made{&b->made};
    for (std::size_t i = 0; i < b->size; ++i) b->records[i] = make(b->first + i, b->tapes[i]);
    return b;
  };
  auto take_all = [&](Batch* b) {
    happens_after(&tape_list::pipeline_start);
    happens_after(&take_turn);
    happens_after(&b->made);
    const ReleaseOnExit turn{&take_turn}, taken{&b->taken};
    for (std::size_t i = 0; i < b->size; ++i) take(b->first + i, b->tapes[i], std::move(b->records[i]));
  };
  const auto filters = tbb::make_filter<void, Batch*>(tbb::filter_mode::serial_in_order, parse) &
                       tbb::make_filter<Batch*, Batch*>(tbb::filter_mode::parallel, make_all) &
                       tbb::make_filter<Batch*, void>(tbb::filter_mode::serial_in_order, take_all);
  happens_before(&tape_list::pipeline_start);
  {
    // All the stages' writes are seen here, also where make or take threw (then batches
    // that make wrote may never have been taken).
    struct Joined {
      const char *parse, *take;
      const std::vector<Batch>& batches;
      ~Joined() {
        happens_after(parse);
        happens_after(take);
        for (const Batch& b : batches) happens_after(&b.made);
      }
    } joined{&parse_turn, &take_turn, batches};
    tbb::parallel_pipeline(tokens, filters);
  }
  return parser.pos;
}

}  // namespace mbsflow
