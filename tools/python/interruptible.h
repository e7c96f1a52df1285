#pragma once
/// Long library calls from Python: the work runs on a worker thread with the GIL released while
/// the calling thread waits, checking for signals every kSignalPollMs (PyErr_CheckSignals acts
/// only on Python's main thread, so it is never called from the library's worker threads). The
/// library's ProgressFn takes the GIL briefly to call the user's progress(stage, fraction). A
/// KeyboardInterrupt (Ctrl-C), an exception raised by progress, or progress returning False stop
/// the work at its next progress report (CancelledError); the first two are then re-raised as
/// they were, the last raises seamvox.CancelledError.
#include <pybind11/pybind11.h>

#include <functional>
#include <memory>

#include "core/system/progress.h"

namespace seamvox::python {

namespace py = pybind11;

constexpr int kSignalPollMs = 50;

class Interruptible {
 public:
  /// progress: None or a callable (stage: str, fraction: float); threads: 0 for all cores.
  Interruptible(py::object progress, int threads);
  ~Interruptible();
  /// The ProgressFn to hand to the library (valid while this object lives).
  ProgressFn progressFn() const;
  /// Runs work as described above; returns when it has finished or stopped. Rethrows its
  /// exception, or the Python exception that cancelled it.
  void run(const std::function<void()>& work);

 private:
  struct State;
  std::shared_ptr<State> state_;
  int threads_;
};

}  // namespace seamvox::python
