#pragma once
// Ctrl-C in Python during a long call: the library's stop handlers replace Python's for the
// call (the run stops after its step, its results file closed), then Python's come back and
// the interrupt is raised as KeyboardInterrupt. Only on Python's main thread, where
// Python itself handles signals.
#include <atomic>
#include <csignal>

#include "bindings.hpp"
#include "mbsflow/runtime/stop_signals.hpp"

namespace mbsflow::python {

class StopGuard {
 public:
  StopGuard() {
    if (PyThreadState_Get()->interp == PyInterpreterState_Main() && PyThread_get_thread_ident() == main_thread())
      flag_ = install_stop_handlers();
  }
  ~StopGuard() {
    if (flag_) restore_stop_handlers();
  }
  StopGuard(const StopGuard&) = delete;
  StopGuard& operator=(const StopGuard&) = delete;
  const std::atomic<bool>* flag() const { return flag_; }
  // After the call stopped: Python's handlers back, then KeyboardInterrupt for SIGINT
  // (SIGTERM is raised again, for Python's own handling of it). No-op when no signal came.
  void raise_if_signalled() {
    const int sig = flag_ ? stop_signal() : 0;
    if (sig == 0) return;
    restore_stop_handlers();
    flag_ = nullptr;
    if (sig == SIGINT) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
    std::raise(sig);
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }

 private:
  // Python's main thread, looked up once (a StopGuard is made at every step of a loop).
  static unsigned long main_thread() {
    static const unsigned long ident =
        py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
    return ident;
  }
  const std::atomic<bool>* flag_ = nullptr;
};

}  // namespace mbsflow::python
