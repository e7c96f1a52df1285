// Resident memory figures (stream/memory) used in reports.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <memory>

#include "core/system/errors.h"
#include "core/system/huge_pages.h"
#include "core/system/memory.h"
#include "core/solve/param_solver.h"

namespace seamvox {
namespace {

TEST(Memory, PeakFollowsATouchedAllocation) {
  const std::uint64_t before = currentResidentBytes();
  ASSERT_GT(before, 0u) << "/proc/self/status not readable";
  EXPECT_GE(peakResidentBytes(), before);
  constexpr std::size_t kBytes = 64u << 20;
  std::unique_ptr<char[]> block(new char[kBytes]);
  std::memset(block.get(), 1, kBytes);  // touch every page so it becomes resident
  const std::uint64_t during = currentResidentBytes();
  EXPECT_GE(during, before + kBytes / 2);
  // VmHWM is updated lazily by the kernel: compare with a margin of a few pages.
  constexpr std::uint64_t kSlack = 4u << 20;
  EXPECT_GE(peakResidentBytes() + kSlack, during);
  volatile char sink = block[kBytes - 1];
  (void)sink;
  block.reset();
  EXPECT_GE(peakResidentBytes() + kSlack, during) << "the peak never goes down";
  EXPECT_GE(peakResidentBytes(), before + kBytes / 2);
}

TEST(Memory, StageMeterSeparatesThePeaksOfConsecutiveStages) {
  constexpr std::size_t kBytes = 96u << 20;
  StageMeter meter;
  {
    std::unique_ptr<char[]> block(new char[kBytes]);
    std::memset(block.get(), 1, kBytes);
    volatile char sink = block[kBytes - 1];
    (void)sink;
  }  // freed before the stage ends: only the peak remembers it
  const StageFigures big = meter.finish("big");
  const StageFigures small = meter.finish("small");
  ASSERT_EQ(meter.stages().size(), 2u);
  EXPECT_EQ(meter.stages()[0].name, "big");
  EXPECT_GE(big.peakBytes, big.endBytes + kBytes / 2) << "the freed block is in the stage's peak";
  EXPECT_GE(meter.peakBytes(), big.peakBytes) << "the whole-run peak keeps every stage's";
  EXPECT_GE(big.seconds, 0.0);
  if (resetPeakResidentBytes()) {
    EXPECT_LT(small.peakBytes + kBytes / 2, big.peakBytes) << "the next stage starts a new peak";
  }
}

TEST(Memory, AvailableMemoryIsKnownOnLinux) {
#ifdef __linux__
  const std::uint64_t available = availableMemoryBytes();
  EXPECT_GT(available, 0u);
  EXPECT_LT(available, std::uint64_t(1) << 50);
#else
  GTEST_SKIP() << "MemAvailable is Linux only";
#endif
}

TEST(Memory, HatFallbackIsRefusedWhenItCannotFit) {
  const std::uint64_t gb = 1000000000ull;
  // A small mesh fits; an unknown amount of memory allows the fallback.
  EXPECT_NO_THROW(checkHatFallbackFits(100000, 8 * gb, "x"));
  EXPECT_NO_THROW(checkHatFallbackFits(20000000, 0, "x"));
  // 20M faces need about 24 GB: refused on an 8 GB machine, with both figures and the reason.
  try {
    checkHatFallbackFits(20000000, 8 * gb, "CHOLMOD: not positive definite");
    FAIL() << "a 24 GB fallback was allowed with 8 GB available";
  } catch (const SolverError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("24.0 GB for 20000000 faces"), std::string::npos) << message;
    EXPECT_NE(message.find("8.0 GB available"), std::string::npos) << message;
    EXPECT_NE(message.find("not positive definite"), std::string::npos) << message;
  }
  EXPECT_NO_THROW(checkHatFallbackFits(20000000, 25 * gb, "x"));
}

/// AnonHugePages of /proc/self/smaps_rollup in bytes, or -1 when unavailable.
long long anonHugePageBytes() {
  std::ifstream in("/proc/self/smaps_rollup");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("AnonHugePages:", 0) == 0) return std::stoll(line.substr(14)) * 1024;
  }
  return -1;
}

TEST(Memory, AdvisedBlocksGetHugePages) {
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::stringstream text;
  text << mode.rdbuf();
  if (text.str().find("[never]") != std::string::npos || text.str().empty() || anonHugePageBytes() < 0) {
    GTEST_SKIP() << "transparent huge pages are not available here";
  }
  const std::size_t bytes = std::size_t(16) << 20;
  char* block = static_cast<char*>(std::malloc(bytes));
  ASSERT_NE(block, nullptr);
  const long long before = anonHugePageBytes();
  adviseHugePages(block, bytes);
  std::memset(block, 7, bytes);
  const long long after = anonHugePageBytes();
  EXPECT_EQ(block[bytes / 2], 7);
  // At least one 2 MB page of the block's 2 MB-aligned interior (12 MB or more) is huge.
  EXPECT_GE(after - before, 2ll << 20) << "before " << before << " after " << after;
  std::free(block);
  // Small blocks and null are left alone.
  adviseHugePages(nullptr, bytes);
  char small[64] = {};
  adviseHugePages(small, sizeof small);
}

}  // namespace
}  // namespace seamvox
