#pragma once
// SIGINT and SIGTERM ask a run to stop after its current step, so that the results file
// is flushed and closed; a second signal ends the process at once.
#include <atomic>

namespace mbsflow::cli {

const std::atomic<bool>* install_stop_handlers();
int stop_signal();  // the signal that asked to stop, 0 if none

}  // namespace mbsflow::cli
