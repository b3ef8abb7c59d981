#include "interrupt.h"

#include <Python.h>
#include <pythread.h>

#include <chrono>

namespace delta::python {

namespace {

/// The shortest time between two looks for a signal: far below the 0.1 s a Ctrl-C may take,
/// far above the cost of taking the GIL.
constexpr std::chrono::milliseconds kSignalLookInterval{5};

thread_local std::chrono::steady_clock::time_point lastLook{};

/// The identity of Python's main thread, where signal handlers run (asked once, GIL held).
unsigned long mainThread() {
  static const unsigned long ident =
      py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  return ident;
}

}  // namespace

bool signalRaised() {
  const auto now = std::chrono::steady_clock::now();
  if (now - lastLook < kSignalLookInterval) return false;
  lastLook = now;
  const py::gil_scoped_acquire acquire;
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  return false;
}

SignalScope::SignalScope() {
  if (PyThread_get_thread_ident() == mainThread()) {
    lastLook = std::chrono::steady_clock::now();
    scope_.emplace(&signalRaised);
  }
}

}  // namespace delta::python
