// Ctrl-C during long calls that run without the GIL: a CancelScope (core/cancel.h) whose poll
// looks for a pending signal, so that a query or grid build stops within some tens of
// milliseconds with KeyboardInterrupt instead of running to its end.
#pragma once

#include <pybind11/pybind11.h>

#include <optional>
#include <utility>

#include "delta/core/cancel.h"

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// The poll of a SignalScope: at most every few milliseconds (time-limited, so that polling
/// often costs nothing), takes the GIL and runs Python's signal handlers (PyErr_CheckSignals);
/// when one raises (KeyboardInterrupt for Ctrl-C), throws it as py::error_already_set, which the
/// binding hands back to Python unchanged.
///
/// Threading: called by the thread that made its scope, without the GIL.
bool signalRaised();

/// While it lives, the long computations of the calling thread stop when a signal handler
/// raises: made with the GIL held, before releasing it. Python runs signal handlers on the main
/// thread only, so on another thread the scope does nothing (its calls run to the end, as
/// before).
///
/// Threading: used on one thread, made with the GIL held.
class SignalScope {
 public:
  SignalScope();

 private:
  std::optional<CancelScope> scope_;
};

}  // namespace delta::python
