#include "mbsflow/runtime/stop_signals.hpp"

#include <csignal>

namespace mbsflow {
namespace {

std::atomic<bool> stop_requested{false};
volatile std::sig_atomic_t signal_seen = 0;
struct sigaction previous_int {}, previous_term {};
bool installed = false;

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
  struct sigaction action {};
  action.sa_handler = on_signal;
  action.sa_flags = SA_RESTART;  // as std::signal on glibc: system calls go on
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, installed ? nullptr : &previous_int);
  sigaction(SIGTERM, &action, installed ? nullptr : &previous_term);
  installed = true;
  return &stop_requested;
}

void restore_stop_handlers() {
  if (installed) {
    sigaction(SIGINT, &previous_int, nullptr);
    sigaction(SIGTERM, &previous_term, nullptr);
  }
  installed = false;
  stop_requested.store(false);
  signal_seen = 0;
}

int stop_signal() { return signal_seen; }

}  // namespace mbsflow
