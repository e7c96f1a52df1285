#pragma once
/// Progress and cancellation for long stages. core never prints: a stage reports through this
/// callback and the caller (tools/) decides whether and how to show it.
#include <functional>
#include <string>

namespace seamvox {

/// Called with a stage name and a fraction in [0, 1]. Return false to cancel: the stage then
/// throws CancelledError. May be called from worker threads, but never concurrently.
using ProgressFn = std::function<bool(const char* stage, double fraction)>;

/// Thin helper: calls fn if set and throws CancelledError when it asks to stop.
void reportProgress(const ProgressFn& fn, const char* stage, double fraction);

}  // namespace seamvox
