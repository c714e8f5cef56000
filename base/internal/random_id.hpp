#pragma once
// A random 64-bit id and its text (16 hex digits): a cluster run's id on the wire, and a
// results file's run_id attribute, which checkpoints name the file by.
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

namespace mbsflow {

inline std::uint64_t random_id() {
  std::random_device rd;
  return (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
}

inline std::string id_text(std::uint64_t id) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(id));
  return buf;
}

}  // namespace mbsflow
