#pragma once
// A temporary folder of this test process's own, removed with what it holds when the
// process exits. ctest runs each test case as a process of its own, and the folders each
// one left behind piled up in /tmp by the hundred. A child that a test forks and that
// leaves through exit() runs the same destructors: only the process that made the folder
// removes it.
#include <unistd.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <system_error>

namespace mbsflow::test {

inline std::filesystem::path process_folder(const std::string& prefix) {
  struct Removed {
    Removed(std::filesystem::path p, pid_t o) : path(std::move(p)), owner(o) {}
    Removed(const Removed&) = delete;
    Removed& operator=(const Removed&) = delete;
    ~Removed() {
      std::error_code ignored;
      if (::getpid() == owner) std::filesystem::remove_all(path, ignored);
    }
    std::filesystem::path path;
    pid_t owner;
  };
  static std::mutex lock;
  static std::map<std::string, Removed> made;
  const std::lock_guard<std::mutex> hold(lock);
  auto it = made.find(prefix);
  if (it == made.end()) {
    const std::filesystem::path path = std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()));
    std::filesystem::create_directories(path);
    it = made.try_emplace(prefix, path, ::getpid()).first;
  }
  return it->second.path;
}

}  // namespace mbsflow::test
