#pragma once
/// Wall time of the pieces of a stage (the stage itself is timed by StageMeter, memory.h).
#include <chrono>

namespace seamvox {

using SteadyClock = std::chrono::steady_clock;

/// Seconds from start to now.
inline double secondsSince(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

}  // namespace seamvox
