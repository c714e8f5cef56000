#include "shared_files.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "mbsflow/error.hpp"

namespace mbsflow::cli {

namespace fs = std::filesystem;

std::string shared_file(const std::string& name) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  std::vector<fs::path> places;
  if (!ec) places.push_back(self.parent_path().parent_path() / "share" / "mbsflow" / name);  // installed
  for (const char* dir : {MBSFLOW_SOURCE_DIR "/apps/viewer", MBSFLOW_SOURCE_DIR "/scripts"}) places.push_back(fs::path(dir) / name);
  for (const fs::path& p : places)
    if (fs::exists(p)) return p.string();
  throw Error("mbsflow: cannot find " + name + " (neither installed in share/mbsflow nor in the source tree " MBSFLOW_SOURCE_DIR ")");
}

std::string three_js_file(const std::string& name) {
  const fs::path p = fs::path("/usr/share/javascript/three") / name;
  if (!fs::exists(p)) throw Error("mbsflow view: " + p.string() + " is missing: install Debian's libjs-three (scripts/install-deps.sh does)");
  return p.string();
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("mbsflow: cannot read " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace mbsflow::cli
