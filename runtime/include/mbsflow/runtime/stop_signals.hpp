#pragma once
// SIGINT and SIGTERM ask a run to stop after its current step (RunOptions::stop), so that
// the results file is flushed and closed; a second signal ends the process at once.
// The CLI installs the handlers for its whole life; an embedding program (the Python
// module) installs them around one run and puts its own back after it.
#include <atomic>

namespace mbsflow {

// Installs the handlers (keeping those they replace) and returns the flag they set.
const std::atomic<bool>* install_stop_handlers();
// Puts back the handlers install_stop_handlers replaced, and clears the flag and the signal.
void restore_stop_handlers();
int stop_signal();  // the signal that asked to stop, 0 if none

}  // namespace mbsflow
