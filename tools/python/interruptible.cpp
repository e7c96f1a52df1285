// Long library calls from Python: GIL released, progress forwarded, Ctrl-C cancels.
#include "tools/python/interruptible.h"

#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "core/system/errors.h"

namespace seamvox::python {

struct Interruptible::State {
  py::object progress;  // touched only with the GIL held
  std::atomic<bool> cancel{false};
  /// The Python exception that cancelled the work (set with the GIL held; first one wins).
  std::optional<py::error_already_set> error;
};

Interruptible::Interruptible(py::object progress, int threads)
    : state_(std::make_shared<State>()), threads_(threads) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) {
    throw py::type_error("progress must be None or a callable (stage: str, fraction: float)");
  }
  state_->progress = std::move(progress);
}

Interruptible::~Interruptible() {
  // The stored Python objects are released with the GIL held (the caller holds it here).
  state_->error.reset();
  state_->progress = py::object();
}

ProgressFn Interruptible::progressFn() const {
  State* state = state_.get();
  return [state](const char* stage, double fraction) {
    if (state->cancel) return false;
    if (state->progress.is_none()) return true;
    py::gil_scoped_acquire gil;
    try {
      const py::object answer = state->progress(stage, fraction);
      if (answer.ptr() == Py_False) state->cancel = true;
    } catch (py::error_already_set& e) {
      if (!state->error) state->error = std::move(e);
      state->cancel = true;
    }
    return !state->cancel;
  };
}

void Interruptible::run(const std::function<void()>& work) {
  std::unique_ptr<tbb::global_control> threads;
  if (threads_ > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(threads_));
  }
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  std::exception_ptr failure;
  std::thread worker;
  {
    py::gil_scoped_release release;
    worker = std::thread([&] {
      try {
        work();
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      done = true;
      finished.notify_all();
    });
  }
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(mutex);
      if (finished.wait_for(lock, std::chrono::milliseconds(kSignalPollMs), [&] { return done; })) break;
    }
    if (!state_->cancel && PyErr_CheckSignals() != 0) {
      py::error_already_set interrupt;  // fetches the KeyboardInterrupt (or a handler's exception)
      if (!state_->error) state_->error = std::move(interrupt);
      state_->cancel = true;
    }
  }
  {
    py::gil_scoped_release release;
    worker.join();
  }
  if (state_->error) {
    py::error_already_set error = std::move(*state_->error);
    state_->error.reset();
    throw error;  // the KeyboardInterrupt or progress's exception, whatever the work ended with
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace seamvox::python
