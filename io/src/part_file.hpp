#pragma once
// A file made under PATH.part and renamed to PATH when complete: the path holds either
// what was there or the whole file, and a failure leaves no .part behind.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "mbsflow/error.hpp"

namespace mbsflow {

template <class Write>
void write_through_part(const std::string& path, Write&& write) {
  const std::string making = path + ".part";
  try {
    write(making);
  } catch (...) {
    std::remove(making.c_str());
    throw;
  }
  if (std::rename(making.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::remove(making.c_str());
    throw InputError("cannot rename " + making + " to " + path + ": " + std::strerror(e));
  }
}

}  // namespace mbsflow
