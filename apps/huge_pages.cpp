#include "huge_pages.hpp"

#include <malloc.h>
#include <sys/stat.h>
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

// Whether the command can gain from huge pages (huge_pages.hpp): it makes models of a size
// its options give (generate, bench) or gets one over the network (worker), or it names a
// file of at least restart_file_bytes (a model of some 35 000 bodies or more, or a large
// checkpoint or results file), as an argument or an option's "=value".
bool worth_restarting(char** argv) {
  constexpr off_t restart_file_bytes = off_t{16} << 20;
  bool command_seen = false;
  for (char** a = argv + 1; *a; ++a) {
    const std::string arg = *a;
    if (!command_seen && !arg.empty() && arg[0] != '-') {
      command_seen = true;
      if (arg == "generate" || arg == "bench" || arg == "worker") return true;
    }
    const std::size_t equals = arg.find('=');
    for (const std::string& path : {arg, equals == std::string::npos ? std::string() : arg.substr(equals + 1)}) {
      struct stat st {};
      if (!path.empty() && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_size >= restart_file_bytes)
        return true;
    }
  }
  return false;
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
  const std::string wanted = environment("MBSFLOW_HUGE_PAGES");
  if (wanted == "0" || (wanted != "1" && !worth_restarting(argv)) || before.find(tunable) != std::string::npos ||
      !kernel_gives_huge_pages() || valgrind)
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
