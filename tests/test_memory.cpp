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

}  // namespace
}  // namespace seamvox
