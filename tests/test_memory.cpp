// Resident memory figures (stream/memory) used in reports.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <memory>
#include <thread>

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
  if (resetPeakResidentBytes()) {
    EXPECT_LT(small.peakBytes + kBytes / 2, big.peakBytes) << "the next stage starts a new peak";
  }
}

TEST(Memory, StageMeterMeasuresEachStagesTimeAndPeak) {
  StageMeter meter;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const StageFigures sleeping = meter.finish("sleep");
  EXPECT_GE(sleeping.seconds, 0.04);
  EXPECT_LT(sleeping.seconds, 10.0);
  const std::uint64_t start = currentResidentBytes();
  constexpr std::size_t kBytes = 64u << 20;
  {
    std::unique_ptr<char[]> block(new char[kBytes]);
    std::memset(block.get(), 1, kBytes);
    volatile char sink = block[kBytes / 3];
    (void)sink;
  }
  const StageFigures allocating = meter.finish("allocate");
  EXPECT_GE(allocating.peakBytes, start + (60u << 20)) << "start " << start;
  EXPECT_LT(allocating.seconds, 10.0);
  EXPECT_GE(meter.peakBytes(), allocating.peakBytes);
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
}

TEST(Memory, AdviceKeepsContentsAndAdvisedMallocHonoursItsContract) {
  // Advice given after the pages were written must not discard them (MADV_HUGEPAGE, not a
  // madvise that frees), for large blocks, small blocks below the threshold and null.
  const std::size_t bytes = std::size_t(16) << 20;
  std::unique_ptr<unsigned char[]> block(new unsigned char[bytes]);
  for (std::size_t i = 0; i < bytes; ++i) block[i] = static_cast<unsigned char>(i * 131 + 7);
  adviseHugePages(block.get(), bytes);
  std::size_t changed = 0;
  for (std::size_t i = 0; i < bytes; ++i) changed += block[i] != static_cast<unsigned char>(i * 131 + 7);
  EXPECT_EQ(changed, 0u);
  char small[64];
  for (int i = 0; i < 64; ++i) small[i] = static_cast<char>(i);
  adviseHugePages(small, sizeof small);
  adviseHugePages(nullptr, bytes);
  for (int i = 0; i < 64; ++i) EXPECT_EQ(small[i], static_cast<char>(i));
  // mallocAdvised: at least one byte for 0, null (not a crash) when the request cannot be met.
  void* zero = mallocAdvised(0);
  EXPECT_NE(zero, nullptr);
  std::free(zero);
  EXPECT_EQ(mallocAdvised(~std::size_t(0) - 4095), nullptr);  // beyond PTRDIFF_MAX: refused
  char* advised = static_cast<char*>(mallocAdvised(bytes));
  ASSERT_NE(advised, nullptr);
  std::memset(advised, 3, bytes);
  EXPECT_EQ(advised[bytes - 1], 3);
  std::free(advised);
}

}  // namespace
}  // namespace seamvox
