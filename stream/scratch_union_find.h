#pragma once
/// detail::UnionFind and detail::ParityUnionFind over ids of a whole mesh (its faces or vertices)
/// within a memory share: the links (per id its distance to its parent, the parity in the top
/// bit; zero: a root) are a ScratchArray, in memory while 4 bytes per id fit the share, else in a
/// scratch file through a page cache of the share. The same steps, so the same roots and
/// parities either way. Lookups in a spatially coherent order (the ids of Morton-ordered faces
/// and of the vertices they name first) mostly hit the cache.
#include <cstdint>
#include <string>

#include "core/mesh/detail_union_find.h"
#include "stream/paged_reader.h"

namespace seamvox {

/// The links of both union-finds; parities (ScratchParityUnionFind) limit the ids to 2^31.
class ScratchLinks {
 public:
  ScratchLinks(ScratchFolder& folder, std::uint64_t n, std::uint64_t memoryBytes, const std::string& stage,
               bool parities);
  std::uint32_t parentOf(std::uint32_t x) { return x - (links_.get(x) & distanceMask_); }
  std::uint8_t parityOf(std::uint32_t x) { return static_cast<std::uint8_t>(links_.get(x) >> 31); }
  void setParent(std::uint32_t x, std::uint32_t p) { links_.set(x, x - p); }
  void setLink(std::uint32_t x, std::uint32_t p, std::uint8_t parity) {
    links_.set(x, (x - p) | (std::uint32_t(parity) << 31));
  }
  std::uint64_t size() const { return links_.size(); }
  bool onDisk() const { return links_.onDisk(); }

 private:
  ScratchArray<std::uint32_t> links_;
  std::uint32_t distanceMask_;
};

class ScratchUnionFind {
 public:
  ScratchUnionFind(ScratchFolder& folder, std::uint64_t n, std::uint64_t memoryBytes, const std::string& stage)
      : links_(folder, n, memoryBytes, stage, false) {}
  std::uint32_t find(std::uint32_t x) { return detail::findRoot(links_, x); }
  /// False when a and b were joined already.
  bool unite(std::uint32_t a, std::uint32_t b) { return detail::uniteRoots(links_, a, b); }
  bool onDisk() const { return links_.onDisk(); }

 private:
  ScratchLinks links_;
};

class ScratchParityUnionFind {
 public:
  ScratchParityUnionFind(ScratchFolder& folder, std::uint64_t n, std::uint64_t memoryBytes, const std::string& stage)
      : links_(folder, n, memoryBytes, stage, true) {}
  std::uint32_t find(std::uint32_t x) { return detail::findRootWithParity(links_, x); }
  bool unite(std::uint32_t a, std::uint32_t b, std::uint8_t relation) {
    return detail::uniteWithParity(links_, a, b, relation);
  }
  /// detail::ParityUnionFind::majorityFlips into flips (n entries, all zero).
  void majorityFlips(ScratchArray<std::uint8_t>& flips) { detail::majorityFlips(links_, links_.size(), flips); }
  bool onDisk() const { return links_.onDisk(); }

 private:
  ScratchLinks links_;
};

}  // namespace seamvox
