#pragma once
// Items that share their parameters: a generated chain's or grid's bushings all have the
// same type, points, frames, stiffness, damping, preload and rest length, and its bodies
// the same mass and inertia. MultibodySystem compiles each distinct set once (JointLaw,
// BodyLaw), so that a million bodies do not hold a million copies of the same numbers,
// and an evaluation streams one copy through the cache instead of one per item.
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "mbsflow/graph/model.hpp"

namespace mbsflow {

struct DistinctIndex {
  std::vector<int> of_item;  // per item, its set: 0, 1, ... in the order of first use
  std::vector<int> first;    // per set, the first item that has it
};

// Items 0..n-1 grouped by key_of(i), an array of 64-bit words: equal means equal bit for
// bit (0.0 and -0.0 differ), so that a shared set computes exactly what each item's own
// copy would. Linear time on average: open addressing over set numbers, at most half
// full, each slot's key recomputed from its set's first item (one int per slot).
template <class KeyOf>
DistinctIndex distinct_by_bits(std::size_t n, KeyOf key_of) {
  DistinctIndex out;
  out.of_item.resize(n);
  std::size_t size = 16;
  while (size < 2 * n) size *= 2;
  std::vector<int> table(size, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto key = key_of(i);
    std::uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (std::uint64_t w : key) {
      h ^= w + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
      h *= 0xff51afd7ed558ccdULL;
    }
    std::size_t slot = (h ^ (h >> 33)) & (size - 1);
    while (table[slot] >= 0 && key_of(static_cast<std::size_t>(out.first[static_cast<std::size_t>(table[slot])])) != key)
      slot = (slot + 1) & (size - 1);
    if (table[slot] < 0) {
      table[slot] = static_cast<int>(out.first.size());
      out.first.push_back(static_cast<int>(i));
    }
    out.of_item[i] = table[slot];
  }
  return out;
}

// The words of a list of doubles and flags, appended to a key.
template <std::size_t N>
struct KeyWords {
  std::array<std::uint64_t, N> words{};
  std::size_t n = 0;
  template <class Values>
  KeyWords& put(const Values& values) {
    for (double v : values) words[n++] = std::bit_cast<std::uint64_t>(v);
    return *this;
  }
};

// What a joint's law (JointLaw) is made of.
inline std::array<std::uint64_t, 34> joint_law_key(const Joint& j) {
  KeyWords<34> k;
  k.put(std::array<double, 1>{j.type == JointType::spring ? 1.0 : 0.0});
  k.put(j.point1).put(j.point2).put(j.frame1.get()).put(j.frame2.get()).put(j.stiffness).put(j.damping).put(j.preload.get());
  k.put(std::array<double, 1>{j.rest_length});
  return k.words;
}

// What a body's mass properties (BodyLaw) are made of.
inline std::array<std::uint64_t, 7> body_law_key(const Body& b) {
  KeyWords<7> k;
  k.put(std::array<double, 1>{b.mass}).put(b.inertia);
  return k.words;
}

}  // namespace mbsflow
