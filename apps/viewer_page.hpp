#pragma once
// The page of mbsflow view: a results file's motion as one self-contained HTML file.
#include <string>

#include "mbsflow/io/results_file.hpp"

namespace mbsflow::cli {

struct ViewerSettings {
  long max_frames = 1000;   // snapshots shown at most (evenly spread, the last included)
  double max_megabytes = 200;  // bound on the motion data in the page
  double refresh_seconds = 0;  // > 0: a live run's page, which reloads itself this often
  int mode = 1;                // a modes file: the mode shown (1: the lowest)
};

struct ViewerPage {
  std::string html;
  long frames = 0, stride = 1;  // snapshots shown, and every how many of the file's
};

// Throws InputError when the file holds no body positions.
ViewerPage viewer_page(const ResultsFile& results, const ViewerSettings& settings);

}  // namespace mbsflow::cli
