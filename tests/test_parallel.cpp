// parallelFor covers every index once, runs one block on the calling thread, passes exceptions.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/system/parallel.h"

namespace seamvox {
namespace {

TEST(Parallel, CoversEveryIndexExactlyOnceInBlocksNoSmallerThanHalfTheGrain) {
  for (std::uint64_t n : {0ull, 1ull, 7ull, 1000ull, 100003ull}) {
    std::vector<std::atomic<int>> hits(n);
    std::atomic<std::uint64_t> smallest{~0ull};
    parallelFor(n, 64, [&](const IndexRange& r) {
      EXPECT_LT(r.begin(), r.end());
      std::uint64_t size = r.end() - r.begin(), seen = smallest.load();
      while (size < seen && !smallest.compare_exchange_weak(seen, size)) {
      }
      for (std::uint64_t i = r.begin(); i != r.end(); ++i) ++hits[i];
    });
    for (std::uint64_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << "n " << n << " i " << i;
    if (n > 64) EXPECT_GE(smallest.load(), 32u);
  }
}

TEST(Parallel, OneBlockRunsOnTheCallingThreadAsOneCall) {
  const std::thread::id caller = std::this_thread::get_id();
  int calls = 0;
  parallelFor(500, 500, [&](const IndexRange& r) {
    ++calls;
    EXPECT_EQ(std::this_thread::get_id(), caller);
    EXPECT_EQ(r.begin(), 0u);
    EXPECT_EQ(r.end(), 500u);
  });
  EXPECT_EQ(calls, 1);
}

TEST(Parallel, ForEachVisitsEveryIndexAndExceptionsPropagate) {
  std::vector<std::atomic<int>> hits(10000);
  parallelForEach(hits.size(), 100, [&](std::uint64_t i) { ++hits[i]; });
  for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
  EXPECT_THROW(parallelForEach(10000, 100, [](std::uint64_t i) {
                 if (i == 5000) throw std::runtime_error("stop");
               }),
               std::runtime_error);
}

}  // namespace
}  // namespace seamvox
