#include "huge_pages.hpp"

#include <malloc.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

namespace mbsflow::cli {
namespace {

constexpr const char* tunable = "glibc.malloc.hugetlb";
constexpr const char* blas_timeout = "OPENBLAS_THREAD_TIMEOUT";  // 2^value cycles of spinning (huge_pages.hpp)

std::string environment(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// THP in "always" or "madvise" mode (not "never", and readable).
bool kernel_gives_huge_pages() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  const std::string modes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return modes.find("[always]") != std::string::npos || modes.find("[madvise]") != std::string::npos;
}

}  // namespace

bool huge_pages_on() {
  const std::string t = environment("GLIBC_TUNABLES"), setting = std::string(tunable) + "=";
  const auto at = t.find(setting);
  const char value = at == std::string::npos || at + setting.size() >= t.size() ? '0' : t[at + setting.size()];
  return value == '1' || value == '2';
}

void restart_with_huge_pages(char** argv) {
  const std::string before = environment("GLIBC_TUNABLES");
  // Under valgrind, /proc/self/exe is valgrind's tool, which will not run by itself.
  const bool valgrind = environment("LD_PRELOAD").find("vgpreload") != std::string::npos;
  if (environment("MBSFLOW_HUGE_PAGES") == "0" || before.find(tunable) != std::string::npos || !kernel_gives_huge_pages() ||
      valgrind)
    return;
  const std::string after = (before.empty() ? "" : before + ":") + tunable +
                            "=1:glibc.malloc.mmap_threshold=4294967295:glibc.malloc.trim_threshold=268435456";
  if (::setenv("GLIBC_TUNABLES", after.c_str(), 1) != 0) return;
  const bool set_blas_timeout = std::getenv(blas_timeout) == nullptr;
  if (set_blas_timeout) ::setenv(blas_timeout, "22", 1);
  ::execv("/proc/self/exe", argv);
  // exec failed (no /proc): go on as we are, without the tunable in the environment
  if (set_blas_timeout) ::unsetenv(blas_timeout);
  if (before.empty())
    ::unsetenv("GLIBC_TUNABLES");
  else
    ::setenv("GLIBC_TUNABLES", before.c_str(), 1);
}

void give_back_free_memory() { ::malloc_trim(0); }

}  // namespace mbsflow::cli
