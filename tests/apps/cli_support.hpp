#pragma once
// Running the mbsflow executable from tests: exit code, stderr, stdout.
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "process_folder.hpp"

namespace fs = std::filesystem;

namespace mbsflow::test {

struct Result {
  int code = -1;
  std::string err;  // stderr (stdout is dropped)
  std::string out;  // stdout, when asked for
};

// Runs `mbsflow ARGS` in directory dir; returns the exit code and stderr.
inline Result run(const std::string& args, const std::string& dir = ".", bool want_stdout = false) {
  const std::string tmp = (fs::temp_directory_path() / ("mbsflow_cli_" + std::to_string(::getpid()) + ".out")).string();
  const std::string cmd = "cd '" + dir + "' && '" + MBSFLOW_EXE + "' " + args + " 2>&1 >'" + tmp + "'";
  Result r;
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.err.append(buf.data(), n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (want_stdout) {
    std::ifstream in(tmp);
    std::stringstream s;
    s << in.rdbuf();
    r.out = s.str();
  }
  fs::remove(tmp);
  return r;
}

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The cells of a CSV line (no quoted commas).
inline std::vector<std::string> csv_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::istringstream cs(line);
  for (std::string cell; std::getline(cs, cell, ',');) cells.push_back(cell);
  return cells;
}

inline std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

inline fs::path scratch(const char* name) {
  const fs::path d = process_folder("mbsflow_test_") / name;
  fs::create_directories(d);
  return d;
}

}  // namespace mbsflow::test
