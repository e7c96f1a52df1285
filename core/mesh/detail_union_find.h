#pragma once
/// Union-find over 32-bit ids with path halving; unite keeps the smaller id as the root, so
/// results do not depend on the order of unions.
#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace seamvox::detail {

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Union-find whose entries carry a parity against their root: flip(a) xor flip(b) = relation.
/// The root is a component's smallest id, as in detail::UnionFind.
struct ParityUnionFind {
  std::vector<std::uint32_t> parent;
  std::vector<std::uint8_t> parity;  // against parent
  explicit ParityUnionFind(std::size_t n) : parent(n), parity(n, 0) {
    for (std::uint32_t i = 0; i < n; ++i) parent[i] = i;
  }
  /// The root of x; x's parity is then against it.
  std::uint32_t find(std::uint32_t x) {
    std::uint32_t root = x;
    std::uint8_t total = 0;
    while (parent[root] != root) total ^= parity[root], root = parent[root];
    // Path compression: every entry on the path points at the root with its own parity.
    while (parent[x] != root) {
      const std::uint32_t next = parent[x];
      const std::uint8_t own = parity[x];
      parent[x] = root;
      parity[x] = total;
      total ^= own;
      x = next;
    }
    return root;
  }
  /// False when a and b are joined already with the other parity (a non-orientable loop).
  bool unite(std::uint32_t a, std::uint32_t b, std::uint8_t relation) {
    const std::uint32_t ra = find(a), rb = find(b);
    const std::uint8_t pa = parity[a] * (a != ra), pb = parity[b] * (b != rb);
    if (ra == rb) return (pa ^ pb) == relation;
    const std::uint32_t lo = std::min(ra, rb), hi = std::max(ra, rb);
    parent[hi] = lo;
    parity[hi] = pa ^ pb ^ relation;
    return true;
  }
  /// Per entry, whether it flips: its parity against its set's smallest id, the whole set turned
  /// over when that flips most of it (a component keeps the orientation most of its faces have).
  std::vector<std::uint8_t> majorityFlips() {
    const std::size_t n = parent.size();
    std::vector<std::uint8_t> flip(n, 0);
    std::unordered_map<std::uint32_t, std::array<std::uint64_t, 2>> tally;  // per root: flipped, entries
    for (std::uint32_t x = 0; x < n; ++x) {
      const std::uint32_t root = find(x);
      flip[x] = root == x ? 0 : parity[x];
      if (flip[x]) ++tally[root][0];
    }
    if (tally.empty()) return flip;
    for (std::uint32_t x = 0; x < n; ++x) {
      const auto it = tally.find(parent[x]);
      if (it != tally.end()) ++it->second[1];
    }
    for (std::uint32_t x = 0; x < n; ++x) {
      const auto it = tally.find(parent[x]);
      if (it != tally.end() && 2 * it->second[0] > it->second[1]) flip[x] ^= 1;
    }
    return flip;
  }
};

}  // namespace seamvox::detail
