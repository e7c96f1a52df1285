#pragma once
/// Union-find over 32-bit ids with path halving; unite keeps the smaller id as the root, so
/// results do not depend on the order of unions.
#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/mesh/mesh_types.h"
#include "core/system/parallel.h"

namespace seamvox::detail {

/// The steps of the union-finds below over any store of links (parentOf(x), setParent(x, p)):
/// find with path halving; unite keeps the smaller root (false when a and b were joined).
template <class Links>
std::uint32_t findRoot(Links& links, std::uint32_t x) {
  for (std::uint32_t up = links.parentOf(x); up != x; up = links.parentOf(x)) {
    const std::uint32_t grandparent = links.parentOf(up);
    links.setParent(x, grandparent);
    x = grandparent;
  }
  return x;
}
template <class Links>
bool uniteRoots(Links& links, std::uint32_t a, std::uint32_t b) {
  a = findRoot(links, a), b = findRoot(links, b);
  if (a == b) return false;
  links.setParent(std::max(a, b), std::min(a, b));
  return true;
}

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) { return findRoot(*this, x); }
  void unite(std::uint32_t a, std::uint32_t b) { uniteRoots(*this, a, b); }
  std::uint32_t parentOf(std::uint32_t x) const { return parent[x]; }
  void setParent(std::uint32_t x, std::uint32_t p) { parent[x] = p; }
};

/// The steps of a union-find with parities over any store of links (parentOf(x), parityOf(x),
/// setLink(x, parent, parity)); ParityUnionFind says what they mean.
template <class Links>
std::uint32_t findRootWithParity(Links& links, std::uint32_t x) {
  std::uint32_t root = x;
  std::uint8_t total = 0;
  for (std::uint32_t up = links.parentOf(root); up != root; up = links.parentOf(root)) {
    total ^= links.parityOf(root);
    root = up;
  }
  // Path compression: every entry on the path points at the root with its own parity.
  for (std::uint32_t up = links.parentOf(x); up != root; up = links.parentOf(x)) {
    const std::uint8_t own = links.parityOf(x);
    links.setLink(x, root, total);
    total ^= own;
    x = up;
  }
  return root;
}
template <class Links>
bool uniteWithParity(Links& links, std::uint32_t a, std::uint32_t b, std::uint8_t relation) {
  const std::uint32_t ra = findRootWithParity(links, a), rb = findRootWithParity(links, b);
  const std::uint8_t pa = a != ra ? links.parityOf(a) : 0, pb = b != rb ? links.parityOf(b) : 0;
  if (ra == rb) return (pa ^ pb) == relation;
  links.setLink(std::max(ra, rb), std::min(ra, rb), pa ^ pb ^ relation);
  return true;
}
/// Per entry x < n, flips.set(x, whether it flips): its parity against its set's smallest id,
/// the whole set turned over when that flips most of it. flips starts all zero.
template <class Links, class Flips>
void majorityFlips(Links& links, std::uint64_t n, Flips& flips) {
  std::unordered_map<std::uint32_t, std::array<std::uint64_t, 2>> tally;  // per root: flipped, entries
  for (std::uint32_t x = 0; x < n; ++x) {
    const std::uint32_t root = findRootWithParity(links, x);
    const std::uint8_t flip = root == x ? 0 : links.parityOf(x);
    if (flip) flips.set(x, 1), ++tally[root][0];
  }
  if (tally.empty()) return;
  // After the finds every entry links to its root.
  for (std::uint32_t x = 0; x < n; ++x) {
    const auto it = tally.find(links.parentOf(x));
    if (it != tally.end()) ++it->second[1];
  }
  for (std::uint32_t x = 0; x < n; ++x) {
    const auto it = tally.find(links.parentOf(x));
    if (it != tally.end() && 2 * it->second[0] > it->second[1]) flips.set(x, flips.get(x) ^ 1);
  }
}

/// Union-find whose entries carry a parity against their root: flip(a) xor flip(b) = relation.
/// The root is a component's smallest id, as in detail::UnionFind.
struct ParityUnionFind {
  std::vector<std::uint32_t> parent;
  std::vector<std::uint8_t> parity;  // against parent
  explicit ParityUnionFind(std::size_t n) : parent(n), parity(n, 0) {
    for (std::uint32_t i = 0; i < n; ++i) parent[i] = i;
  }
  /// The root of x; x's parity is then against it.
  std::uint32_t find(std::uint32_t x) { return findRootWithParity(*this, x); }
  /// False when a and b are joined already with the other parity (a non-orientable loop).
  bool unite(std::uint32_t a, std::uint32_t b, std::uint8_t relation) { return uniteWithParity(*this, a, b, relation); }
  /// Per entry, whether it flips: its parity against its set's smallest id, the whole set turned
  /// over when that flips most of it (a component keeps the orientation most of its faces have).
  std::vector<std::uint8_t> majorityFlips() {
    struct Flips {
      std::vector<std::uint8_t> flip;
      std::uint8_t get(std::uint32_t x) const { return flip[x]; }
      void set(std::uint32_t x, std::uint8_t v) { flip[x] = v; }
    } flips{std::vector<std::uint8_t>(parent.size(), 0)};
    detail::majorityFlips(*this, parent.size(), flips);
    return std::move(flips.flip);
  }
  std::uint32_t parentOf(std::uint32_t x) const { return parent[x]; }
  std::uint8_t parityOf(std::uint32_t x) const { return parity[x]; }
  void setLink(std::uint32_t x, std::uint32_t p, std::uint8_t relation) { parent[x] = p, parity[x] = relation; }
};

/// Per face, the smallest face of its set: faces f > g sharing an interior edge are joined when
/// joined(f, g). A union-find over both cores whose links point to smaller ids only (a root is
/// linked under the other only by a compare-and-swap while it is still a root; path halving writes
/// an ancestor over a non-root), so every root is its set's smallest face whatever the order of
/// the unions; each entry ends pointing at its root.
template <class Table, class Joined>
std::vector<std::uint32_t> smallestFaceOfSets(const Table& table, Joined&& joined) {
  const std::uint32_t nf = table.numFaces();
  std::vector<std::uint32_t> parent(nf);
  parallelForEach(nf, 1u << 16, [&](std::uint64_t f) { parent[f] = static_cast<std::uint32_t>(f); });
  const auto load = [&](std::uint32_t x) { return __atomic_load_n(&parent[x], __ATOMIC_RELAXED); };
  const auto find = [&](std::uint32_t x) {
    for (std::uint32_t up = load(x); up != x; up = load(x)) {
      const std::uint32_t grandparent = load(up);
      if (grandparent != up) __atomic_store_n(&parent[x], grandparent, __ATOMIC_RELAXED);
      x = grandparent;
    }
    return x;
  };
  parallelFor(nf, 1u << 14, [&](const IndexRange& range) {
    for (std::uint32_t f = range.begin(); f != range.end(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const CornerId o = table.opposite(3 * f + k);
        if (o == kInvalidId || o / 3 >= f || !joined(f, o / 3)) continue;  // each pair from its larger face
        std::uint32_t a = f, b = o / 3;
        for (;;) {
          a = find(a), b = find(b);
          if (a == b) break;
          if (a < b) std::swap(a, b);
          std::uint32_t expected = a;
          if (__atomic_compare_exchange_n(&parent[a], &expected, b, false, __ATOMIC_ACQ_REL, __ATOMIC_RELAXED)) break;
        }
      }
    }
  });
  parallelForEach(nf, 1u << 14, [&](std::uint64_t f) {
    const std::uint32_t root = find(static_cast<std::uint32_t>(f));
    __atomic_store_n(&parent[f], root, __ATOMIC_RELAXED);
  });
  return parent;
}

}  // namespace seamvox::detail
