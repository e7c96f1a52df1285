#pragma once
/// Resident memory of this process, for reports (Linux /proc/self/status; 0 elsewhere), and a
/// meter of time and memory per pipeline stage.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace seamvox {

/// Peak resident set size so far (VmHWM), in bytes.
std::uint64_t peakResidentBytes();
/// Current resident set size (VmRSS), in bytes.
std::uint64_t currentResidentBytes();
/// Memory the system can give without swapping (MemAvailable of /proc/meminfo), in bytes; 0 when
/// unknown.
std::uint64_t availableMemoryBytes();
/// Hands memory the allocator keeps after frees back to the system (glibc's malloc_trim; nothing
/// elsewhere). Many mid-sized blocks freed at once (a stage's per-group vectors) otherwise stay
/// resident and add to the next stage's peak.
void releaseFreedMemory();
/// Resets the kernel's peak (VmHWM) to the current resident size, so the next peakResidentBytes
/// is the peak since now. Returns false where unsupported (the peak then keeps growing).
bool resetPeakResidentBytes();

/// Time and memory of one stage: wall seconds, the peak resident size during the stage and the
/// resident size when it ended.
struct StageFigures {
  std::string name;
  double seconds = 0.0;
  std::uint64_t peakBytes = 0, endBytes = 0;
};

/// Measures consecutive stages: finish(name) closes the stage that began at the previous finish
/// (or at construction), after releasing freed memory (releaseFreedMemory). Resets the kernel's peak at every stage boundary, so whole-process
/// peaks must be read from peakBytes(), not peakResidentBytes().
class StageMeter {
 public:
  StageMeter();
  /// Closes the current stage and starts the next one; returns its figures.
  const StageFigures& finish(const std::string& name);
  const std::vector<StageFigures>& stages() const { return stages_; }
  /// Peak resident size over all stages so far (and the current one).
  std::uint64_t peakBytes() const;
  /// Wall seconds since construction.
  double totalSeconds() const;

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_, mark_;
  std::vector<StageFigures> stages_;
  std::uint64_t peakBefore_ = 0;  // peak over closed stages (and before the meter)
  bool perStage_ = false;         // the kernel peak can be reset
};

}  // namespace seamvox
