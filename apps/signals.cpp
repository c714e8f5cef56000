#include "signals.hpp"

#include <csignal>

namespace mbsflow::cli {
namespace {

std::atomic<bool> stop_requested{false};
volatile std::sig_atomic_t signal_seen = 0;

extern "C" void on_signal(int sig) {
  if (stop_requested.load()) {  // second signal: give up at once
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  signal_seen = sig;
  stop_requested.store(true);
}

}  // namespace

const std::atomic<bool>* install_stop_handlers() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  return &stop_requested;
}

int stop_signal() { return signal_seen; }

}  // namespace mbsflow::cli
