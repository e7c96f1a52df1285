#pragma once
/// Wall time of the pieces of a stage (the stage itself is timed by StageMeter, memory.h).
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace seamvox {

using SteadyClock = std::chrono::steady_clock;

/// Seconds from start to now.
inline double secondsSince(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

/// Appends the seconds since the previous finish (or since it was made) under a name.
class StageClock {
 public:
  explicit StageClock(std::vector<std::pair<std::string, double>>& out) : out_(out) {}
  void finish(const char* name) {
    out_.emplace_back(name, secondsSince(start_));
    start_ = SteadyClock::now();
  }

 private:
  std::vector<std::pair<std::string, double>>& out_;
  SteadyClock::time_point start_ = SteadyClock::now();
};

}  // namespace seamvox
