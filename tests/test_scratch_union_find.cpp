// The union-finds and arrays of stream/scratch_union_find and stream/paged_reader give what the
// in-memory ones give whether their links fit their share of the memory or live on disk
// behind a page cache much smaller than the array (pages written back and read again).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/mesh/detail_union_find.h"
#include "stream/scratch_union_find.h"
#include "testing.h"

namespace seamvox {
namespace {

constexpr std::uint32_t kIds = 300000;  // 1.2 MB of links against a cache of two 16 KiB pages

/// Pairs to unite: mostly near each other (as ids of nearby faces), some across the whole range.
std::vector<std::pair<std::uint32_t, std::uint32_t>> randomPairs(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> any(0, kIds - 1), near(0, 64);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::uint32_t i = 0; i < kIds; ++i) {
    const std::uint32_t a = any(rng);
    const std::uint32_t b = i % 50 == 0 ? any(rng) : std::min(kIds - 1, a + near(rng));
    pairs.emplace_back(a, b);
  }
  return pairs;
}

TEST(ScratchUnionFind, SameRootsInMemoryAndOnDisk) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const auto pairs = randomPairs(7);
  detail::UnionFind expected(kIds);
  for (const std::uint64_t memory : {std::uint64_t(0), std::uint64_t(4) * kIds}) {
    SCOPED_TRACE(memory);
    {
      ScratchUnionFind sets(folder, kIds, memory, "test");
      EXPECT_EQ(sets.onDisk(), memory == 0);
      detail::UnionFind reference(kIds);
      std::size_t joined = 0;
      for (const auto& [a, b] : pairs) {
        const bool merged = reference.find(a) != reference.find(b);
        reference.unite(a, b);
        EXPECT_EQ(sets.unite(a, b), merged);
        joined += merged;
      }
      EXPECT_GT(joined, kIds / 2);
      std::size_t differ = 0;
      for (std::uint32_t x = kIds; x-- > 0;) differ += sets.find(x) != reference.find(x);
      EXPECT_EQ(differ, 0u);
    }
    EXPECT_EQ(folder.bytesInUse(), 0u) << "the links' file outlived its union-find";
  }
}

TEST(ScratchParityUnionFind, SameParitiesAndFlipsInMemoryAndOnDisk) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const auto pairs = randomPairs(11);
  std::mt19937 rng(3);
  std::vector<std::uint8_t> relation;
  for (std::size_t i = 0; i < pairs.size(); ++i) relation.push_back(rng() % 7 == 0);  // mostly consistent
  detail::ParityUnionFind reference(kIds);
  std::vector<bool> accepted;
  for (std::size_t i = 0; i < pairs.size(); ++i) accepted.push_back(reference.unite(pairs[i].first, pairs[i].second, relation[i]));
  const std::vector<std::uint8_t> flips = reference.majorityFlips();
  std::size_t flipped = 0, rejected = 0;
  for (const std::uint8_t f : flips) flipped += f;
  for (const bool a : accepted) rejected += !a;
  EXPECT_GT(flipped, 1000u);
  EXPECT_GT(rejected, 100u) << "no unions against the parities: that path is untested";
  for (const std::uint64_t memory : {std::uint64_t(0), std::uint64_t(4) * kIds}) {
    SCOPED_TRACE(memory);
    ScratchParityUnionFind sets(folder, kIds, memory, "test");
    EXPECT_EQ(sets.onDisk(), memory == 0);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) differ += sets.unite(pairs[i].first, pairs[i].second, relation[i]) != accepted[i];
    EXPECT_EQ(differ, 0u);
    ScratchArray<std::uint8_t> got(folder, kIds, memory / 4, "test");
    EXPECT_EQ(got.onDisk(), memory == 0);
    sets.majorityFlips(got);
    differ = 0;
    for (std::uint32_t x = 0; x < kIds; ++x) differ += got.get(x) != flips[x];
    EXPECT_EQ(differ, 0u);
  }
}

TEST(ScratchArray, StartsZeroAndKeepsWritesThroughEvictions) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  ScratchArray<std::uint64_t> a(folder, 100000, 1, "test");
  ASSERT_TRUE(a.onDisk());
  std::mt19937 rng(5);
  std::vector<std::uint64_t> model(100000, 0);
  for (int i = 0; i < 200000; ++i) {
    const std::uint32_t at = rng() % 100000;
    if (i % 3 == 0) {
      model[at] = rng();
      a.set(at, model[at]);
    } else {
      ASSERT_EQ(a.get(at), model[at]) << "record " << at;
    }
  }
  for (std::uint32_t at = 0; at < 100000; ++at) ASSERT_EQ(a.get(at), model[at]);
}

}  // namespace
}  // namespace seamvox
