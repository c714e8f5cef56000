#pragma once
// Items listed per body in compressed rows (CSR), each body's items in the order they were
// given: a counting sort, linear in bodies and items. A million bodies' lists so take two
// flat arrays, not a million small vectors, and no comparison sort.
#include <cstddef>
#include <span>
#include <vector>

namespace mbsflow {

// for_each(emit) calls emit(body, item) for every (body, item) pair, in the order wanted
// within each body; it is called twice, and must emit the same pairs both times.
// start gets bodies + 1 offsets into list.
template <class ForEach>
void build_body_csr(std::size_t bodies, ForEach for_each, std::vector<int>& start, std::vector<int>& list) {
  start.assign(bodies + 1, 0);
  for_each([&](int body, int) { ++start[static_cast<std::size_t>(body) + 1]; });
  for (std::size_t b = 0; b < bodies; ++b) start[b + 1] += start[b];
  list.resize(static_cast<std::size_t>(start[bodies]));
  std::vector<int> next(start.begin(), start.end() - 1);
  for_each([&](int body, int item) { list[static_cast<std::size_t>(next[static_cast<std::size_t>(body)]++)] = item; });
}

// The same lists held together, read per body.
struct BodyCsr {
  std::vector<int> start, list;
  std::span<const int> operator[](std::size_t body) const {
    return {list.data() + start[body], static_cast<std::size_t>(start[body + 1] - start[body])};
  }
};

}  // namespace mbsflow
