// Resident memory figures (stream/memory) used in reports.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "stream/memory.h"

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

}  // namespace
}  // namespace seamvox
