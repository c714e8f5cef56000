#pragma once
// Files the program reads at run time: its own (the viewer page, the plot script), found
// installed beside the program (PREFIX/share/mbsflow) or in the source tree it was built
// from, and three.js from Debian's libjs-three.
#include <string>

namespace mbsflow::cli {

std::string shared_file(const std::string& name);    // Error when found nowhere
std::string three_js_file(const std::string& name);  // Error naming the package when missing
std::string file_text(const std::string& path);      // the whole file; Error when it cannot be read

}  // namespace mbsflow::cli
