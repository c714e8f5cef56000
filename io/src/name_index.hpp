#pragma once
// Names to indices for the model reader: each body name a joint refers to is found in
// constant time. The table holds only (index, hash) slots, open addressing with linear
// probing, at most half full; the names stay in the model, reached through name_of(i).
// An unordered_map<string, int> spends a heap node per name (a million-body model reads
// two million names), this about 16 bytes.
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

namespace mbsflow {

class NameIndex {
 public:
  // The index already stored under name; else stores `index` under it and returns -1.
  // name_of(index) is read only by later calls.
  template <class NameOf>
  int insert(std::string_view name, int index, NameOf name_of) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    const std::uint32_t h = hash(name);
    for (std::size_t s = h & mask();; s = (s + 1) & mask()) {
      Slot& slot = slots_[s];
      if (slot.index < 0) {
        slot = {index, h};
        ++used_;
        return -1;
      }
      if (slot.hash == h && name_of(slot.index) == name) return slot.index;
    }
  }
  // The index stored under name, or -1.
  template <class NameOf>
  int find(std::string_view name, NameOf name_of) const {
    if (slots_.empty()) return -1;
    const std::uint32_t h = hash(name);
    for (std::size_t s = h & mask();; s = (s + 1) & mask()) {
      const Slot& slot = slots_[s];
      if (slot.index < 0) return -1;
      if (slot.hash == h && name_of(slot.index) == name) return slot.index;
    }
  }

 private:
  struct Slot {
    int index = -1;
    std::uint32_t hash = 0;
  };
  static std::uint32_t hash(std::string_view s) { return static_cast<std::uint32_t>(std::hash<std::string_view>{}(s)); }
  std::size_t mask() const { return slots_.size() - 1; }
  void grow() {
    std::vector<Slot> old(slots_.empty() ? 16 : 2 * slots_.size());
    old.swap(slots_);
    for (const Slot& o : old) {
      if (o.index < 0) continue;
      std::size_t s = o.hash & mask();
      while (slots_[s].index >= 0) s = (s + 1) & mask();
      slots_[s] = o;
    }
  }
  std::vector<Slot> slots_;  // a power of two in size
  std::size_t used_ = 0;
};

}  // namespace mbsflow
