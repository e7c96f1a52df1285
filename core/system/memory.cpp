#include "core/system/memory.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <cstdio>
#include <cstring>

namespace seamvox {
namespace {

/// Value of a "Name:   123 kB" line of /proc/self/status, in bytes (0 when unavailable).
std::uint64_t statusBytes(const char* field, const char* path = "/proc/self/status") {
  std::FILE* file = std::fopen(path, "r");
  if (!file) return 0;
  char line[256];
  std::uint64_t bytes = 0;
  const std::size_t length = std::strlen(field);
  while (std::fgets(line, sizeof line, file)) {
    if (std::strncmp(line, field, length) == 0 && line[length] == ':') {
      unsigned long long kb = 0;
      if (std::sscanf(line + length + 1, "%llu", &kb) == 1) bytes = kb * 1024ull;
      break;
    }
  }
  std::fclose(file);
  return bytes;
}

}  // namespace

std::uint64_t peakResidentBytes() { return statusBytes("VmHWM"); }
std::uint64_t currentResidentBytes() { return statusBytes("VmRSS"); }
std::uint64_t availableMemoryBytes() { return statusBytes("MemAvailable", "/proc/meminfo"); }

bool resetPeakResidentBytes() {
  // Linux >= 4.0: writing 5 to clear_refs resets VmHWM to the current RSS.
  std::FILE* file = std::fopen("/proc/self/clear_refs", "w");
  if (!file) return false;
  const bool written = std::fputs("5", file) >= 0;
  return std::fclose(file) == 0 && written;
}

StageMeter::StageMeter() : start_(Clock::now()), mark_(start_) {
  peakBefore_ = peakResidentBytes();
  perStage_ = resetPeakResidentBytes();
}

void releaseFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

const StageFigures& StageMeter::finish(const std::string& name) {
  releaseFreedMemory();
  const Clock::time_point now = Clock::now();
  StageFigures figures;
  figures.name = name;
  figures.seconds = std::chrono::duration<double>(now - mark_).count();
  figures.peakBytes = peakResidentBytes();
  figures.endBytes = currentResidentBytes();
  if (figures.peakBytes < figures.endBytes) figures.peakBytes = figures.endBytes;
  if (figures.peakBytes > peakBefore_) peakBefore_ = figures.peakBytes;
  stages_.push_back(figures);
  if (perStage_) perStage_ = resetPeakResidentBytes();
  mark_ = Clock::now();
  return stages_.back();
}

std::uint64_t StageMeter::peakBytes() const {
  const std::uint64_t now = peakResidentBytes();
  return now > peakBefore_ ? now : peakBefore_;
}

double StageMeter::totalSeconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

}  // namespace seamvox
